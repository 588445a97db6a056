"""MoveIt scene/request YAML loading (MotionBenchMaker problems)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MBM_TARBALL, needs_mbm

from maru_planner.collision import CollisionChecker
from maru_planner.errors import InvalidRequest, InvalidScene
from maru_planner.robot import load_example_robot
from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN
from maru_planner.scene.motion_bench_maker import iter_mbm_problems
from maru_planner.scene.moveit import quaternion_matrix, request_from_moveit, scene_from_moveit

SCENE = """
robot_state:
  multi_dof_joint_state:
    transforms: [{translation: [0, 0, 0], rotation: [0, 0, 0, 1]}]
    joint_names: [virtual_joint]
world:
  collision_objects:
    - id: can
      primitive_poses:
        - position: [0.5, 0.3, 0.1]
          orientation: [0, 0, 0.7071067811865476, 0.7071067811865476]
      primitives:
        - type: cylinder
          dimensions: [0.14, 0.03]
    - id: shelf
      primitives:
        - {type: box, dimensions: [0.7, 0.5, 0.04]}
        - {type: sphere, dimensions: [0.05]}
      primitive_poses:
        - {position: [0.6, 0, 0.2], orientation: [0, 0, 0, 1]}
        - {position: [0.6, 0, 0.4], orientation: [0, 0, 0, 1]}
"""

REQUEST = """
group_name: panda_arm
planner_id: RRTConnect
allowed_planning_time: 5
start_state:
  joint_state:
    name: [panda_joint1, panda_joint2, panda_finger_joint1]
    position: [0.1, -0.5, 0.04]
goal_constraints:
  - joint_constraints:
      - {joint_name: panda_joint1, position: 1.0}
      - {position: -0.2, joint_name: panda_joint2}
"""


def test_scene_primitives_follow_moveit_conventions():
    scene = scene_from_moveit(SCENE)
    assert list(scene.obstacles) == ["can", "shelf/0", "shelf/1"]
    can = scene.obstacles["can"]
    assert can.type == "cylinder" and can.length == pytest.approx(0.14) and can.radius == pytest.approx(0.03)
    np.testing.assert_allclose(can.pose[:3, 3], [0.5, 0.3, 0.1])
    np.testing.assert_allclose(can.pose[:3, 0], [0, 1, 0], atol=1e-12)  # 90 deg about z (x y z w order)
    assert scene.obstacles["shelf/0"].size == pytest.approx((0.7, 0.5, 0.04))
    assert scene.obstacles["shelf/1"].radius == pytest.approx(0.05)


def test_robot_root_offset_moves_obstacles_into_the_robot_frame():
    shifted = SCENE.replace("translation: [0, 0, 0]", "translation: [0.5, 0, 0]")
    scene = scene_from_moveit(shifted)
    np.testing.assert_allclose(scene.obstacles["can"].pose[:3, 3], [0.0, 0.3, 0.1])


def test_quaternion_is_xyzw_and_normalised():
    np.testing.assert_allclose(quaternion_matrix([0, 0, 0, 2]), np.eye(3))
    np.testing.assert_allclose(quaternion_matrix([1, 0, 0, 0]), np.diag([1, -1, -1]), atol=1e-12)
    with pytest.raises(InvalidScene):
        quaternion_matrix([0, 0, 0, 0])


@pytest.mark.parametrize(
    "old, new",
    [
        ("type: cylinder", "type: cone"),  # unsupported primitive
        ("dimensions: [0.14, 0.03]", "dimensions: [0.14]"),  # a cylinder needs height and radius
    ],
)
def test_bad_scene_content_is_named(old, new):
    with pytest.raises(InvalidScene, match="can"):
        scene_from_moveit(SCENE.replace(old, new))


def test_mesh_objects_are_refused_not_dropped():
    text = SCENE.replace("    - id: shelf\n", "    - id: shelf\n      meshes: [{vertices: [], triangles: []}]\n")
    with pytest.raises(InvalidScene, match="shelf.*meshes"):
        scene_from_moveit(text)


def test_request_start_goal_and_fixed_fingers():
    req = request_from_moveit(REQUEST, fixed_joints=PANDA_FINGERS_OPEN)
    assert req.group == "panda_arm" and req.planner_id == "RRTConnect" and req.allowed_planning_time == 5.0
    assert req.start == {
        "panda_joint1": 0.1,
        "panda_joint2": -0.5,
        "panda_finger_joint1": 0.065,
        "panda_finger_joint2": 0.065,
    }
    assert req.goal == {
        "panda_joint1": 1.0,
        "panda_joint2": -0.2,
        "panda_finger_joint1": 0.065,
        "panda_finger_joint2": 0.065,
    }


def test_request_without_joint_goal_is_rejected():
    with pytest.raises(InvalidRequest, match="joint_constraints"):
        request_from_moveit(REQUEST.split("goal_constraints")[0])
    with pytest.raises(InvalidRequest, match="not found"):
        request_from_moveit("/nonexistent/request.yaml")


@needs_mbm
def test_motionbenchmaker_problems_load_and_start_goal_are_free():
    problems = list(
        iter_mbm_problems(
            MBM_TARBALL, sets=["box", "cage", "table_pick"], limit_per_set=2, fixed_joints=PANDA_FINGERS_OPEN
        )
    )
    assert [p.name for p in problems] == [
        "box/0001",
        "box/0002",
        "cage/0001",
        "cage/0002",
        "table_pick/0001",
        "table_pick/0002",
    ]
    robot = load_example_robot("panda")
    checker = CollisionChecker(robot)
    for problem in problems:
        assert len(problem.scene) >= 3
        assert problem.request.group == "panda_arm"
        assert set(problem.request.goal) >= {f"panda_joint{i}" for i in range(1, 8)}
        checker.set_scene(problem.scene)
        for values in (problem.request.start, problem.request.goal):
            q = np.zeros(robot.nq)
            q[robot.joint_indices(list(values))] = list(values.values())
            assert checker.is_valid(q), f"{problem.name}: {checker.colliding_pairs(q)}"
    box = problems[0]
    names = list(box.scene.obstacles)
    assert "base" in names and box.scene.obstacles["base"].type == "box"
