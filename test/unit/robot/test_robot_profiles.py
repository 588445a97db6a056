"""Robot profiles: adding a robot is one table entry (files, limits, end effectors, IK strategies)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from maru_planner.errors import InvalidRequest
from maru_planner.paths import urdf_path
from maru_planner.robot import RobotModel, load_example_robot, profiles
from maru_planner.robot.ik import solve_ik
from maru_planner.robot.robots import maru1


@pytest.fixture
def toy_profile():
    """A second UR5 with its own limits, end effector and an IK strategy that records its calls."""
    calls = []

    def recording_strategy(robot, targets, q_seed, group, *, deadline=None, is_valid=None):
        calls.append(group)
        return None  # not a request it answers: the numeric IK takes over

    profile = dataclasses.replace(
        profiles.PROFILES["ur5"], name="ur5_slow", acceleration_limits=0.5, end_effectors={"flange": "ee_link"},
        ik_strategies=(recording_strategy,),
    )  # fmt: skip
    profiles.PROFILES[profile.name] = profile
    yield profile, calls
    del profiles.PROFILES[profile.name]


def test_a_new_robot_is_one_profile_entry(toy_profile):
    profile, calls = toy_profile
    robot = load_example_robot("ur5_slow")
    assert robot.name == "ur5_slow" and robot.end_effectors == {"flange": "ee_link"}
    assert np.all(robot.acceleration_limits == 0.5) and "manipulator" in robot.groups
    q = robot.random_configuration(np.random.default_rng(1))
    target = robot.frame_pose(q, "ee_link")
    solution = solve_ik(robot, {"ee_link": target}, robot.neutral(), "manipulator", rng=np.random.default_rng(2))
    assert np.abs(robot.frame_pose(solution, "ee_link") - target).max() < 1e-6
    assert calls == ["manipulator"]


def test_maru1_profile_and_loading_by_path_share_the_ik_strategies():
    by_name = RobotModel.maru1()
    by_path = RobotModel.from_urdf(urdf_path("maru1_upper_body.urdf"), urdf_path("maru1_upper_body.srdf"))
    expected = (maru1.one_arm_strategy, maru1.two_hands_strategy)
    assert by_name.ik_strategies == by_path.ik_strategies == expected
    assert load_example_robot("panda").ik_strategies == ()


def test_two_hand_strategy_answers_only_its_request():
    robot = RobotModel.maru1()
    q = robot.named_state("home")
    hands = {f: robot.frame_pose(q, f) for f in ("r_hand", "l_hand")}
    assert maru1.two_hands_strategy(robot, hands, q, "right_arm") is None
    assert maru1.one_arm_strategy(robot, hands, q, "right_arm") is None
    solution = maru1.two_hands_strategy(robot, hands, robot.neutral(), "upper_body")
    assert all(np.abs(robot.frame_pose(solution, f) - T).max() < 1e-6 for f, T in hands.items())


def test_unknown_robot_names_the_known_ones():
    with pytest.raises(InvalidRequest, match="known.*maru1"):
        RobotModel.from_profile("r2d2")
