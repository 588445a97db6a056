"""Robot-agnostic loading: example-robot-data robots with FK, IK and collision checks."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.collision import CollisionChecker
from maru_planner.errors import InvalidRequest
from maru_planner.robot import load_example_robot
from maru_planner.robot.ik import solve_ik
from maru_planner.scene import Obstacle, Scene


@pytest.mark.parametrize("name, group, nq", [("panda", "arm", 9), ("ur5", "manipulator", 6)])
def test_arm_fk_ik_collision(name, group, nq):
    robot = load_example_robot(name)
    assert robot.nq == nq == len(robot.joint_names) == len(robot.lower_limits)
    assert group in robot.groups
    frame = next(iter(robot.end_effectors.values()))
    rng = np.random.default_rng(0)
    cc = CollisionChecker(robot)
    valid = 0
    for _ in range(8):
        q = robot.random_configuration(rng)
        target = robot.frame_pose(q, frame)
        assert target.shape == (4, 4) and robot.frame_jacobian(q, frame).shape == (6, nq)
        sol = solve_ik(robot, {frame: target}, robot.neutral(), group, rng=rng)
        assert np.abs(robot.frame_pose(sol, frame) - target).max() < 1e-6
        valid += cc.is_valid(q)
    assert cc.check_count == 8
    # an obstacle at the end effector makes the configuration invalid, moved away it is valid again
    q = robot.named_state(next(iter(robot.named_states))) if robot.named_states else robot.neutral()
    tip = robot.frame_pose(q, frame)[:3, 3]
    scene = Scene([Obstacle("ball", "sphere", radius=0.05, pose=tip)])
    cc.set_scene(scene)
    assert not cc.is_valid(q)
    scene.move("ball", tip + [0, 0, 3.0])
    assert cc.is_valid(q) == (cc.colliding_pairs(q) == [])


def test_tiago_and_talos_load_with_nq_equal_nv():
    tiago = load_example_robot("tiago")
    assert tiago.model.nq == tiago.model.nv == tiago.nq
    assert "wheel_left_joint" not in tiago.joint_names and "arm" in tiago.groups
    assert CollisionChecker(tiago).is_valid(tiago.neutral())  # links touching at rest are not checked
    talos = load_example_robot("talos")
    assert talos.nq == talos.model.nv == 32 and "r_arm" in talos.groups
    q = talos.named_state("half_sitting")
    assert talos.frame_pose(q, talos.end_effectors["right"]).shape == (4, 4)


def test_unknown_robot():
    with pytest.raises(InvalidRequest, match="known"):
        load_example_robot("r2d2")
