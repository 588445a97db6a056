"""MuJoCo arms from their URDFs (physics/arm_model.py, physics/arm_sim.py): holding a pose under gravity, the
servo's gains and limits, robot-obstacle contacts with their depth, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.errors import InvalidJointCount, InvalidJointNames, InvalidRequest, InvalidState
from maru_planner.physics.arm_model import ServoGains, build_arm_model
from maru_planner.physics.arm_sim import ArmSim
from maru_planner.robot.robots.panda import mbm_panda
from maru_planner.scene import Obstacle, Scene


@pytest.fixture(scope="module")
def panda_mbm():
    return mbm_panda()


def _random_pose(robot, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return robot.lower_limits + (0.1 + 0.8 * rng.random(robot.nq)) * (robot.upper_limits - robot.lower_limits)


@pytest.mark.parametrize("which", ["maru1", "panda"])
def test_arm_holds_a_pose_under_gravity(which, maru1, panda_mbm):
    robot = maru1 if which == "maru1" else panda_mbm
    arm = build_arm_model(robot)
    assert arm.joint_names == robot.joint_names and arm.model.opt.timestep == pytest.approx(0.001)
    sim = ArmSim(arm)
    for seed in range(2):
        q = _random_pose(robot, seed)
        sim.reset(q)
        sim.step(500)
        state = sim.state()
        assert np.max(np.abs(state.positions - q)) < 1e-4
        assert np.max(np.abs(state.velocities)) < 1e-3
        assert np.all(np.abs(state.efforts) <= arm.effort_limits + 1e-9)
        assert sim.saturated_steps == 0 and not sim.contacts.deepest


def test_without_gravity_compensation_the_spring_holds_within_its_saturation_error(panda_mbm):
    gains = ServoGains(gravity_compensation=False, saturation_error=0.02)
    arm = build_arm_model(panda_mbm, gains=gains)
    np.testing.assert_allclose(arm.kp, panda_mbm.model.effortLimit / 0.02)
    sim = ArmSim(arm)
    q = _random_pose(panda_mbm, 3)
    sim.reset(q)
    sim.step(800)
    sag = np.abs(sim.state().positions - q)
    assert 1e-4 < np.max(sag) < 0.02  # gravity pulls, the spring holds


def test_effort_limit_clamps_the_servo_and_is_counted(maru1):
    arm = build_arm_model(maru1)
    sim = ArmSim(arm)
    q = maru1.neutral().copy()
    sim.reset(q)
    target = q.copy()
    target[0] += 0.5  # 0.5 rad error: kp * 0.5 >> 30 N m
    sim.command(target, np.zeros(maru1.nq))
    sim.step(20)
    assert sim.saturated_steps > 0
    assert abs(sim.state().efforts[0]) == pytest.approx(arm.effort_limits[0])


def test_contacts_report_the_link_the_obstacle_and_the_penetration_depth(maru1):
    q = maru1.neutral().copy()
    hand = maru1.frame_pose(q, "r_hand")[:3, 3]
    scene = Scene([Obstacle("post", "box", size=(0.05, 0.05, 0.05), pose=list(hand)),
                   Obstacle("far", "sphere", radius=0.05, pose=[3.0, 0.0, 0.0])])  # fmt: skip
    arm = build_arm_model(maru1, scene)
    assert arm.obstacle_names == ["post", "far"]
    sim = ArmSim(arm)
    sim.reset(q)
    contacts = sim.step()
    assert contacts and {c.obstacle for c in contacts} == {"post"}
    assert all(c.depth > 0.0 for c in contacts)
    assert "r_arm" in contacts[0].link or "r_hand" in contacts[0].link
    assert sim.contacts.max_depth >= max(c.depth for c in contacts) and sim.contacts.steps_in_contact == 1


def test_attached_objects_are_robot_geoms_that_touch_obstacles(maru1):
    q = maru1.neutral().copy()
    hand = maru1.frame_pose(q, "r_hand")
    table = Obstacle("table", "box", size=(0.1, 0.1, 0.05), pose=list(hand[:3, 3] - [0.0, 0.0, 0.3]))
    scene = Scene([table])
    free = ArmSim(build_arm_model(maru1, scene))
    free.reset(q)
    assert free.step() == []
    rod_in_world = np.eye(4)
    rod_in_world[:3, 3] = hand[:3, 3] - [0.0, 0.0, 0.15]  # from the hand down into the table
    scene.attach("rod", "r_hand", obstacle=Obstacle("rod", "box", size=(0.02, 0.02, 0.3),
                                                    pose=np.linalg.inv(hand) @ rod_in_world))  # fmt: skip
    carrying = ArmSim(build_arm_model(maru1, scene))
    carrying.reset(q)
    assert {(c.link, c.obstacle) for c in carrying.step()} == {("rod", "table")}


def test_bad_input_is_a_typed_error(maru1):
    sim = ArmSim(build_arm_model(maru1))
    with pytest.raises(InvalidJointCount, match="expected 13"):
        sim.reset(np.zeros(3))
    q = maru1.neutral().copy()
    q[4] = np.nan
    with pytest.raises(InvalidState, match="r_arm_j4"):
        sim.reset(q)
    with pytest.raises(InvalidJointNames, match="wrist"):
        sim.arm.joint_indices(["waist_yaw", "wrist"])
    with pytest.raises(InvalidRequest, match="saturation_error"):
        ServoGains(saturation_error=0.0)
