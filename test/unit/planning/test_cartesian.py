"""Cartesian paths on the core: straight lines of a link, waypoints, jumps, collisions, certification, errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from maru_planner.collision.certify import PathCertifier
from maru_planner.planning import MotionPlanner, PlanStatus
from maru_planner.planning.cartesian import CartesianRequest, default_link
from maru_planner.robot import RobotModel
from maru_planner.scene import Obstacle, Scene

# both arms well conditioned (hand Jacobians' smallest singular value ~0.15)
MARU_START = (-0.9, 0.25, 1.75, 1.66, 1.9, 0.0, -2.55, 0.15, 1.35, 0.83, 1.87, -3.17, -1.41)


@pytest.fixture(scope="module")
def maru1():
    robot = RobotModel.maru1()
    return robot, dict(zip(robot.joint_names, MARU_START, strict=True))


@pytest.fixture(scope="module")
def panda():
    robot = RobotModel.from_profile("panda")
    q = robot.named_state("default")
    return robot, dict(zip(robot.joint_names, q.tolist(), strict=True))


def _shifted(robot, start: dict, link: str, offset) -> np.ndarray:
    q = np.array([start[n] for n in robot.joint_names])
    pose = robot.frame_pose(q, link).copy()
    pose[:3, 3] += offset
    return pose


def _positions_along(robot, result, start: dict, link: str) -> np.ndarray:
    """The link's positions at every trajectory sample (FK on the sampled joint values)."""
    q = np.array([start[n] for n in robot.joint_names])
    idx = robot.joint_indices(result.trajectory.joint_names)
    points = []
    for row in result.trajectory.positions:
        q[idx] = row
        points.append(robot.frame_pose(q, link)[:3, 3].copy())
    return np.array(points)


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    t = np.clip((points - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * (b - a)), axis=1)


@pytest.mark.parametrize(
    "robot_fixture, group",
    [("maru1", "right_arm"), ("maru1", "left_arm"), ("maru1", "torso_right_arm"), ("panda", "arm")],
)
def test_straight_line_is_followed_to_the_end_and_certified(request, robot_fixture, group):
    robot, start = request.getfixturevalue(robot_fixture)
    link = default_link(robot, group)
    begin = _shifted(robot, start, link, (0.0, 0.0, 0.0))
    goal = _shifted(robot, start, link, (0.05, -0.03, 0.08))
    result = MotionPlanner.from_scene(robot, Scene()).cartesian_path(
        CartesianRequest(group, start, [goal], max_step=0.01, jump_threshold=10.0)
    )
    assert result.status is PlanStatus.SUCCESS, result.message
    assert result.fraction == 1.0 and result.certified and result.stop_reason == ""
    points = _positions_along(robot, result, start, link)
    # the timed trajectory blends corners by at most 0.01 rad, i.e. millimetres at the hand
    assert _distance_to_segment(points, begin[:3, 3], goal[:3, 3]).max() < 5e-3
    assert np.linalg.norm(points[-1] - goal[:3, 3]) < 1e-3
    velocity = np.abs(result.trajectory.velocities).max(axis=0)
    assert np.all(velocity <= robot.velocity_limits[robot.joint_indices(result.joint_names)] * (1 + 1e-6))


def test_waypoints_are_visited_in_turn(maru1):
    robot, start = maru1
    waypoints = [_shifted(robot, start, "r_hand", d) for d in ((0.06, 0, 0), (0.06, 0.06, 0), (0.0, 0.06, 0.03))]
    result = MotionPlanner.from_scene(robot, Scene()).cartesian_path(
        CartesianRequest("right_arm", start, waypoints, max_step=0.01)
    )
    assert result.fraction == 1.0, result.message
    q = np.array([start[n] for n in robot.joint_names])
    idx = robot.joint_indices(result.joint_names)
    reached = []
    for row in result.path:
        q[idx] = row
        reached.append(robot.frame_pose(q, "r_hand")[:3, 3].copy())
    for waypoint in waypoints:
        assert np.linalg.norm(np.array(reached) - waypoint[:3, 3], axis=1).min() < 1e-3


def test_an_obstacle_on_the_line_stops_the_path_before_it(maru1):
    robot, start = maru1
    goal = _shifted(robot, start, "r_hand", (0.0, 0.0, 0.25))
    wall = Obstacle("plate", "box", size=(0.4, 0.4, 0.02), pose=goal[:3, 3] - (0, 0, 0.1))
    scene = Scene([wall])
    result = MotionPlanner.from_scene(robot, scene).cartesian_path(CartesianRequest("right_arm", start, [goal]))
    assert result.status is PlanStatus.SUCCESS, result.message
    assert 0.0 < result.fraction < 1.0
    assert "plate" in result.stop_reason or "certified" in result.stop_reason
    base = np.array([start[n] for n in robot.joint_names])
    full = np.repeat(base[None], len(result.path), axis=0)
    full[:, robot.joint_indices(result.joint_names)] = result.path
    assert PathCertifier(robot, scene, safety_margin=0.0).certify_path(full).valid  # an independent certifier


def test_jump_threshold_cuts_at_the_first_long_joint_step(maru1):
    robot, start = maru1
    goal = _shifted(robot, start, "r_hand", (0.0, 0.1, 0.0))
    planner = MotionPlanner.from_scene(robot, Scene())
    loose = planner.cartesian_path(CartesianRequest("right_arm", start, [goal], jump_threshold=10.0))
    tight = planner.cartesian_path(CartesianRequest("right_arm", start, [goal], jump_threshold=0.5))
    assert loose.fraction == 1.0
    # some step is at least the mean step, so a threshold of half the mean always cuts (maybe at the first step)
    assert tight.fraction < 1.0 and "jump" in (tight.stop_reason or tight.message)


def test_unreachable_line_stops_with_a_reason_and_a_first_step_out_of_reach_is_no_ik(maru1):
    robot, start = maru1
    planner = MotionPlanner.from_scene(robot, Scene())
    far = _shifted(robot, start, "r_hand", (0.0, 0.0, 1.5))
    partial = planner.cartesian_path(CartesianRequest("right_arm", start, [far]))
    assert partial.success and 0.0 < partial.fraction < 1.0 and "no IK" in partial.stop_reason
    nothing = planner.cartesian_path(CartesianRequest("right_arm", start, [far], max_step=1.0))
    assert nothing.status is PlanStatus.NO_IK_SOLUTION and nothing.fraction == 0.0 and nothing.trajectory is None


@pytest.mark.parametrize(
    "changes, status",
    [
        ({"link": "no_such_link"}, PlanStatus.INVALID_LINK),
        ({"group": "upper_body"}, PlanStatus.INVALID_LINK),  # two hands: the link must be named
        ({"max_step": 0.0}, PlanStatus.INVALID_REQUEST),
        ({"waypoints": []}, PlanStatus.INVALID_REQUEST),
        ({"start": {}}, PlanStatus.NO_START_STATE),
        ({"group": "legs"}, PlanStatus.INVALID_GROUP),
    ],
)
def test_bad_requests_get_their_status(maru1, changes, status):
    robot, start = maru1
    fields = {"group": "right_arm", "start": start, "waypoints": [_shifted(robot, start, "r_hand", (0, 0, 0.05))]}
    result = MotionPlanner.from_scene(robot, Scene()).cartesian_path(CartesianRequest(**{**fields, **changes}))
    assert result.status is status, result.message
    assert result.message and result.trajectory is None


def test_cli_writes_a_cartesian_path_and_refuses_bad_offsets(tmp_path, capsys):
    from maru_planner.planning.cli import EXIT_BAD_INPUT, EXIT_OK, main

    out = tmp_path / "line.json"
    start = ["0", "-0.785", "0", "-2.356", "0", "1.571", "0.785"]
    args = ["--robot", "panda", "--group", "arm", "--start", *start, "--quiet"]
    assert main([*args, "--cartesian", "0.1", "0", "0", "0.1", "0.1", "0", "--json", str(out)]) == EXIT_OK
    answer = json.loads(out.read_text())
    assert answer["fraction"] == 1.0 and answer["certified"] and answer["link"] == "panda_hand_tcp"
    assert answer["trajectory"]["joint_names"] == [f"panda_joint{i}" for i in range(1, 8)]
    assert main([*args, "--cartesian", "0.1", "0", "--json", str(out)]) == EXIT_BAD_INPUT
    assert main([*args, "--cartesian", "0.1", "0", "0", "--link", "nope", "--json", str(out)]) == EXIT_BAD_INPUT
    assert "INVALID_LINK" in capsys.readouterr().err
