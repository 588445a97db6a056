"""Unit tests of the planning node's message <-> core conversions, and the in-process node helper."""

from __future__ import annotations

import math

import numpy as np
import pytest
from geometry_msgs.msg import Pose, PoseStamped
from shape_msgs.msg import SolidPrimitive

from maru_planner import errors
from maru_planner.planning.types import PlanStats, PlanStatus
from maru_planner.ros import planning_conversions as conv
from maru_planner.trajectory import Trajectory
from maru_planner_interfaces.msg import PlanningError


def _rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


@pytest.mark.parametrize("axis,angle", [((1, 0, 0), 0.3), ((0, 1, 1), 2.9), ((1, -2, 0.5), math.pi), ((0, 0, 1), 0)])
def test_pose_matrix_round_trip(axis, angle):
    transform = np.eye(4)
    transform[:3, :3] = _rotation(axis, angle)
    transform[:3, 3] = [0.1, -0.2, 0.3]
    back = conv.pose_to_matrix(conv.matrix_to_pose(transform))
    np.testing.assert_allclose(back, transform, atol=1e-9)


def test_pose_quaternion_is_normalised_and_checked():
    pose = Pose()
    pose.orientation.w = 2.0
    np.testing.assert_allclose(conv.pose_to_matrix(pose), np.eye(4))
    pose.orientation.w = 0.0
    with pytest.raises(errors.InvalidRequest, match="quaternion is zero"):
        conv.pose_to_matrix(pose)
    pose.orientation.w = 1.0
    pose.position.x = math.nan
    with pytest.raises(errors.InvalidRequest, match="NaN"):
        conv.pose_to_matrix(pose)


def test_named_values_match_by_name_and_reject_bad_lists():
    assert conv.named_values(["b", "a"], [2.0, 1.0], "goal") == {"b": 2.0, "a": 1.0}
    with pytest.raises(errors.InvalidJointCount, match="2 joint names but 1 positions"):
        conv.named_values(["a", "b"], [1.0], "goal")
    with pytest.raises(errors.InvalidJointNames, match="'a' appears twice"):
        conv.named_values(["a", "a"], [1.0, 2.0], "goal")


def test_pose_goals_check_frames_and_lengths():
    stamped = PoseStamped()
    stamped.pose.orientation.w = 1.0
    stamped.header.frame_id = "base_link"
    goals = conv.pose_goals([stamped], ["r_hand"], "base_link")
    assert list(goals) == ["r_hand"]
    with pytest.raises(errors.InvalidRequest, match="1 goal_poses but 2 goal_links"):
        conv.pose_goals([stamped], ["r_hand", "l_hand"], "base_link")
    stamped.header.frame_id = "map"
    with pytest.raises(errors.InvalidRequest, match="frame 'map'"):
        conv.pose_goals([stamped], ["r_hand"], "base_link")


def _primitive(kind, dims):
    return SolidPrimitive(type=kind, dimensions=list(dims))


def _unit_pose():
    pose = Pose()
    pose.position.x = 0.5
    pose.orientation.w = 1.0
    return pose


@pytest.mark.parametrize(
    "kind,dims,fields",
    [
        (SolidPrimitive.BOX, [0.1, 0.2, 0.3], {"size": [0.1, 0.2, 0.3]}),
        (SolidPrimitive.SPHERE, [0.1], {"radius": 0.1}),
        (SolidPrimitive.CYLINDER, [0.4, 0.05], {"length": 0.4, "radius": 0.05}),
    ],
)
def test_primitive_obstacle_round_trip(kind, dims, fields):
    obstacle = conv.primitive_to_obstacle("thing", _primitive(kind, dims), _unit_pose())
    assert obstacle["name"] == "thing"
    for key, value in fields.items():
        assert obstacle[key] == pytest.approx(value)
    assert np.asarray(obstacle["pose"])[0, 3] == pytest.approx(0.5)
    msg = conv.obstacle_to_msg(obstacle, "base_link")
    assert msg.shape.type == kind
    assert list(msg.shape.dimensions) == pytest.approx(dims)
    assert msg.pose.position.x == pytest.approx(0.5)


@pytest.mark.parametrize(
    "kind,dims,match",
    [
        (7, [0.1], "shape type 7"),
        (SolidPrimitive.BOX, [0.1, 0.2], "needs 3 dimensions"),
        (SolidPrimitive.SPHERE, [-0.1], "finite and > 0"),
        (SolidPrimitive.CYLINDER, [math.nan, 0.1], "finite and > 0"),
    ],
)
def test_malformed_primitive_names_the_obstacle(kind, dims, match):
    with pytest.raises(errors.InvalidScene, match=match) as info:
        conv.primitive_to_obstacle("crate", _primitive(kind, dims), _unit_pose())
    assert "'crate'" in str(info.value)


def test_every_core_status_and_error_has_its_own_code():
    assert set(conv.STATUS_CODES) == {status.name for status in PlanStatus}
    codes = list(conv.STATUS_CODES.values())
    assert len(set(codes)) == len(codes)
    error_classes = [
        cls
        for cls in vars(errors).values()
        if isinstance(cls, type) and issubclass(cls, errors.MaruError) and cls not in (errors.MaruError,)
    ]
    for cls in error_classes:
        exc = cls("boom")
        if cls is errors.InCollision:
            assert conv.error_code(exc) == PlanningError.INTERNAL_ERROR  # abstract: never raised as is
            continue
        assert conv.error_code(exc) != PlanningError.INTERNAL_ERROR, cls
    assert conv.error_code(errors.PlanningTimedOut("t")) == PlanningError.TIMED_OUT
    assert conv.error_code(errors.InvalidGroup("g")) == PlanningError.INVALID_GROUP_NAME
    assert conv.error_code(RuntimeError("x")) == PlanningError.INTERNAL_ERROR


def test_error_message_keeps_the_core_text_and_source():
    msg = conv.error_msg(errors.InvalidState("joint 'r_elbow' = 4.0 is above its upper limit 2.6"))
    assert msg.code == PlanningError.INVALID_ROBOT_STATE
    assert "r_elbow" in msg.message
    assert msg.source == "validation"
    assert conv.error_msg(None).code == PlanningError.SUCCESS


def test_trajectory_and_stats_messages():
    traj = Trajectory(
        joint_names=["a", "b"],
        times=np.array([0.0, 0.5, 1.25]),
        positions=np.array([[0.0, 1.0], [0.5, 1.5], [1.0, 2.0]]),
        velocities=np.zeros((3, 2)),
        accelerations=np.zeros((3, 2)),
    )
    msg = conv.trajectory_msg(traj, "base_link")
    names, times, positions = conv.trajectory_positions(msg)
    assert names == ["a", "b"]
    np.testing.assert_allclose(times, [0.0, 0.5, 1.25])
    np.testing.assert_allclose(positions, traj.positions)
    assert msg.points[2].time_from_start.sec == 1 and msg.points[2].time_from_start.nanosec == 250_000_000
    stats = conv.stats_msg(PlanStats(planner_id="PRM", nodes=12, collision_checks=99, solve_time=0.5, seed=None))
    assert (stats.planner_id, stats.nodes, stats.collision_checks, stats.seed) == ("PRM", 12, 99, -1)
    assert stats.solve_time == pytest.approx(0.5)


@pytest.mark.ros
def test_background_node_serves_in_process(rclpy_session):
    """The in-process node (for demos): namespaced services, parameter overrides, an empty scene."""
    from conftest import SpinningNode

    from maru_planner.ros.planning_client import PlanningClient
    from maru_planner.ros.planning_node import BackgroundPlanningNode

    joints = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
    start = dict(zip(joints, (-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25), strict=True))
    goal = dict(start, r_arm_j4=1.1)
    with BackgroundPlanningNode(namespace="inproc", scene_file="none", workers=1, default_planner="PRM"):
        spinning = SpinningNode("inproc_client")
        try:
            client = PlanningClient(node=spinning.node, namespace="/inproc")
            assert client.get_scene(timeout=30.0).obstacles == []
            response = client.plan(goal, start=start, time_budget=10.0, seed=1)
            assert response.error.code == PlanningError.SUCCESS, response.error.message
            assert response.stats.planner_id == "PRM"
        finally:
            spinning.destroy()
