"""Attached objects: they move with their link, collide with the scene and the robot (exact checker, sphere
checker, certifier, planner), detach where they are, round-trip through YAML, and bad operations get typed errors."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner import errors
from maru_planner.collision import CollisionChecker
from maru_planner.collision.certify import PathCertifier
from maru_planner.collision.spheres import SphereCollisionChecker
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.config import COLLISION_MODELS
from maru_planner.robot import RobotModel
from maru_planner.robot.attached import robot_with_attached
from maru_planner.scene import Obstacle, Scene

Q = np.array((-0.9, 0.25, 1.75, 1.66, 1.9, 0.0, -2.55, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25))  # collision-free


@pytest.fixture(scope="module")
def robot():
    return RobotModel.maru1()


def _offset(pose: np.ndarray, dz: float) -> np.ndarray:
    """``pose`` moved ``dz`` along its own z axis."""
    out = pose.copy()
    out[:3, 3] += dz * pose[:3, 2]
    return out


def _scene_with_bar(robot) -> tuple[Scene, np.ndarray]:
    """A long bar held 0.3 m out along the hand's z axis, attached to r_hand where it is."""
    hand = robot.frame_pose(Q, "r_hand")
    scene = Scene([Obstacle("bar", "box", size=(0.04, 0.04, 0.2), pose=_offset(hand, 0.3))])
    scene.attach("bar", "r_hand", hand)
    return scene, hand


def test_attached_object_moves_with_its_link(robot):
    scene, hand = _scene_with_bar(robot)
    assert "bar" not in scene.obstacles and scene.attached["bar"].link == "r_hand"
    carrying = robot_with_attached(robot, scene)
    assert np.allclose(carrying.frame_pose(Q, "bar"), _offset(hand, 0.3))
    moved = Q.copy()
    moved[robot.joint_indices(["r_arm_j1", "waist_yaw"])] += (0.3, -0.2)
    expected = _offset(robot.frame_pose(moved, "r_hand"), 0.3)
    assert np.allclose(carrying.frame_pose(moved, "bar"), expected)


@pytest.mark.parametrize("checker_class", [CollisionChecker, SphereCollisionChecker])
def test_attached_object_collides_with_the_scene_but_not_with_touch_links(robot, checker_class):
    scene, hand = _scene_with_bar(robot)
    scene.add(Obstacle("post", "sphere", radius=0.03, pose=_offset(hand, 0.3)[:3, 3]))
    carrying = robot_with_attached(robot, scene)
    checker = checker_class(carrying, scene)
    assert not checker.is_valid(Q)
    assert ("bar", "post") in {tuple(sorted(p)) for p in checker.colliding_pairs(Q)}
    scene.remove("post")
    assert checker_class(carrying, scene).is_valid(Q)  # the bar touches its own hand: never checked


def test_attached_object_collides_with_the_robot_unless_a_touch_link(robot):
    hand = robot.frame_pose(Q, "r_hand")
    torso = robot.frame_pose(Q, "torso")
    # a rod from the hand to the torso: it crosses the robot's own links
    middle = 0.5 * (hand[:3, 3] + torso[:3, 3])
    length = float(np.linalg.norm(hand[:3, 3] - torso[:3, 3]))
    local = np.linalg.inv(hand) @ np.r_[middle, 1.0]
    rod = Obstacle("rod", "sphere", radius=0.45 * length, pose=local[:3])
    scene = Scene()
    scene.attach("rod", "r_hand", obstacle=rod)
    pairs = CollisionChecker(robot_with_attached(robot, scene), scene).colliding_pairs(Q)
    touched = sorted({b if a == "rod" else a for a, b in pairs if "rod" in (a, b)})
    assert touched, "the rod should hit some link"
    loose = Scene()
    loose.attach("rod", "r_hand", touch_links=touched, obstacle=rod)
    pairs = CollisionChecker(robot_with_attached(robot, loose), loose).colliding_pairs(Q)
    assert not any("rod" in pair for pair in pairs)


@pytest.mark.parametrize("model", COLLISION_MODELS)
def test_certifier_and_planner_see_the_attached_object(robot, model):
    scene, hand = _scene_with_bar(robot)
    planner = MotionPlanner.from_scene(robot, scene, PlannerConfig(collision_model=model))
    start = dict(zip(robot.joint_names, Q.tolist(), strict=True))
    # an obstacle where the bar is (not the hand): the start collides only because of the bar
    scene.add(Obstacle("post", "sphere", radius=0.03, pose=_offset(hand, 0.3)[:3, 3]))
    goal = {n: float(v) for n, v in zip(robot.joint_names, Q) if n.startswith("r_arm")}
    result = planner.plan(MotionRequest("right_arm", start=start, goal_joints=goal, seed=1))
    assert result.status is PlanStatus.START_IN_COLLISION and "bar" in result.message
    scene.remove("post")
    carrying = robot_with_attached(robot, scene)
    moved = Q.copy()
    moved[robot.joint_indices(["r_arm_j1"])] += 0.6
    sweep = robot_with_attached(robot, scene).frame_pose(moved, "bar")
    scene.add(Obstacle("in_the_way", "sphere", radius=0.03, pose=sweep[:3, 3]))
    path = np.array([Q, moved])
    assert not PathCertifier(carrying, CollisionChecker(carrying, scene)).certify_path(path).valid
    assert PathCertifier(robot, CollisionChecker(robot, scene)).certify_path(path).valid  # without the bar: free


def test_detach_puts_the_object_back_where_it_is(robot):
    scene, _ = _scene_with_bar(robot)
    moved = Q.copy()
    moved[robot.joint_indices(["waist_yaw"])] += 0.4
    carrying = robot_with_attached(robot, scene)
    held = carrying.frame_pose(moved, "bar")
    placed = scene.detach("bar", robot.frame_pose(moved, "r_hand"))
    assert not scene.attached and np.allclose(scene.obstacles["bar"].pose, held) and placed.name == "bar"
    assert robot_with_attached(carrying, scene) is robot  # nothing attached: the bare robot again


def test_scene_yaml_round_trips_attached_objects(robot, tmp_path):
    scene, _ = _scene_with_bar(robot)
    scene.attach("cup", "l_hand", touch_links=["l_arm_link5"],
                 obstacle=Obstacle("cup", "cylinder", radius=0.03, length=0.1, pose=(0, 0, 0.05)))  # fmt: skip
    path = tmp_path / "scene.yaml"
    path.write_text(scene.to_yaml())
    again = Scene.from_yaml(path)
    assert list(again.attached) == ["bar", "cup"]
    assert again.attached["cup"].touch_links == ("l_arm_link5",)
    assert np.allclose(again.attached["bar"].obstacle.pose, scene.attached["bar"].obstacle.pose)
    carrying = robot_with_attached(robot, again)
    assert np.allclose(carrying.frame_pose(Q, "cup"), _offset(robot.frame_pose(Q, "l_hand"), 0.05))


def test_bad_attach_and_detach_operations_raise_typed_errors(robot):
    scene, hand = _scene_with_bar(robot)
    with pytest.raises(errors.ObjectAlreadyAttached, match="bar"):
        scene.attach("bar", "r_hand", hand)
    with pytest.raises(errors.ObjectAlreadyAttached, match="bar"):
        scene.add(Obstacle("bar", "sphere", radius=0.1))
    with pytest.raises(errors.InvalidObject, match="ghost"):
        scene.attach("ghost", "r_hand", hand)
    with pytest.raises(errors.InvalidObject, match="ghost"):
        scene.detach("ghost", hand)
    scene.attach("tray", "no_such_link", obstacle=Obstacle("tray", "box", size=(0.1, 0.1, 0.01)))
    with pytest.raises(errors.InvalidLink, match="no_such_link"):
        robot_with_attached(robot, scene)
    planner = MotionPlanner.from_scene(robot, Scene())
    with pytest.raises(errors.InvalidLink):
        planner.set_scene(scene)
