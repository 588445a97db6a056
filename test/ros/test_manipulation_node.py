"""End-to-end tests of planning_node's manipulation services through real rclpy clients (node in its own process):
query_planners, compute_fk, check_state_validity, compute_cartesian_path, ApplyScene ATTACH/DETACH and
PlanMotion path constraints. The node (Maru-1, desk + box scene) is started once; tests run in file order.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import connected_planning_client

pytestmark = pytest.mark.ros

Q_FREE = (-0.9, 0.25, 1.75, 1.66, 1.9, 0.0, -2.55, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25)  # free in the desk scene


@pytest.fixture(scope="module")
def client(planner_node, tester):
    return connected_planning_client(tester, planner_node)


@pytest.fixture(scope="module")
def robot():
    from maru_planner.robot import RobotModel

    return RobotModel.maru1()


def _state(robot, q=Q_FREE) -> dict[str, float]:
    return dict(zip(robot.joint_names, q, strict=True))


def _matrix(pose) -> np.ndarray:
    from maru_planner.ros.planning_conversions import pose_to_matrix

    return pose_to_matrix(pose)


def _code(name: str) -> int:
    from maru_planner_interfaces.msg import PlanningError

    return getattr(PlanningError, name)


def test_query_planners_lists_the_registry_and_cbirrt(client):
    from maru_planner.planning.planners.registry import PLANNERS

    response = client.query_planners()
    by_id = {p.id: p for p in response.planners}
    assert list(by_id) == list(PLANNERS)
    assert response.default_planner in by_id
    assert "path_constraints" in by_id["CBiRRT"].capabilities
    for planner_id, spec in PLANNERS.items():
        listed = {p.name: p for p in by_id[planner_id].parameters}
        assert set(listed) == set(spec.params)
        assert set(by_id[planner_id].capabilities) == set(spec.capabilities)
        for name, param in spec.params.items():
            assert listed[name].description == param.description
            assert listed[name].lower == (-math.inf if param.lower is None else param.lower)


def test_compute_fk_matches_the_model(client, robot):
    response = client.compute_fk(_state(robot), ["r_hand", "l_hand"])
    assert response.error.code == _code("SUCCESS"), response.error.message
    assert list(response.links) == ["r_hand", "l_hand"]
    q = np.array(Q_FREE)
    for link, stamped in zip(response.links, response.poses, strict=True):
        assert stamped.header.frame_id == "base_link"
        assert np.allclose(_matrix(stamped.pose), robot.frame_pose(q, link), atol=1e-9)
    every = client.compute_fk(_state(robot))
    assert "torso" in every.links and len(every.links) == len(every.poses)
    unknown = client.compute_fk(_state(robot), ["no_such_link"])
    assert unknown.error.code == _code("INVALID_LINK_NAME") and "no_such_link" in unknown.error.message


def test_check_state_validity_reports_pairs_clearance_and_constraint_violation(client, robot):
    from maru_planner_interfaces.msg import PathConstraints

    free = client.check_state_validity(_state(robot))
    assert free.error.code == _code("SUCCESS") and free.valid and free.clearance > 0 and len(free.closest_pair) == 2
    hit = client.check_state_validity(_state(robot, robot.neutral()))  # the left arm in the torso
    assert not hit.valid and hit.clearance <= 0
    assert ("torso", "l_arm_link3") in set(zip(hit.contact_first, hit.contact_second, strict=True))
    constraints = PathConstraints(orientation_link="r_hand")
    constraints.orientation.w = 1.0  # identity: the hand at Q_FREE is far from it
    tolerance = constraints.orientation_tolerance
    tolerance.x = tolerance.y = tolerance.z = 0.1
    tilted = client.check_state_validity(_state(robot), constraints)
    assert not tilted.valid and tilted.orientation_violation > 0.1 and tilted.position_violation == 0.0
    constraints.orientation_link = "nope"
    assert client.check_state_validity(_state(robot), constraints).error.code == _code("INVALID_LINK_NAME")


def test_compute_cartesian_path_follows_a_line_and_refuses_bad_links(client, robot):
    from maru_planner.ros.planning_conversions import trajectory_positions

    q = np.array(Q_FREE)
    goal = robot.frame_pose(q, "r_hand").copy()
    goal[:3, 3] += (0.0, 0.0, 0.08)
    response = client.cartesian_path([goal], start=_state(robot), group="right_arm", jump_threshold=5.0)
    assert response.error.code == _code("SUCCESS"), response.error.message
    assert response.fraction == 1.0 and response.stop_reason == ""
    names, _times, positions = trajectory_positions(response.trajectory)
    q[robot.joint_indices(names)] = positions[-1]
    assert np.linalg.norm(robot.frame_pose(q, "r_hand")[:3, 3] - goal[:3, 3]) < 1e-3
    two_hands = client.cartesian_path([goal], start=_state(robot), group="upper_body")
    assert two_hands.error.code == _code("INVALID_LINK_NAME")
    unknown = client.cartesian_path([goal], start=_state(robot), group="right_arm", link="no_link")
    assert unknown.error.code == _code("INVALID_LINK_NAME") and unknown.fraction == 0.0


def test_attach_moves_with_the_hand_collides_and_detaches_where_it_is(client, robot):
    q = np.array(Q_FREE)
    hand = robot.frame_pose(q, "r_hand")
    over_desk = np.eye(4)
    over_desk[:3, 3] = (0.3, -0.25, 0.05)  # reaches into the desk top (z <= 0.02)
    added = client.attach("probe", "r_hand", shape="sphere", dimensions=[0.05], pose=over_desk,
                          robot_state=_state(robot))  # fmt: skip
    assert added.error.code == _code("SUCCESS"), added.error.message
    assert "probe" not in added.obstacle_names
    scene = client.get_scene()
    assert "attached:" in scene.scene_yaml and "probe" in scene.scene_yaml
    hit = client.check_state_validity(_state(robot))
    pairs = {frozenset(p) for p in zip(hit.contact_first, hit.contact_second, strict=True)}
    assert not hit.valid and frozenset(("probe", "desk")) in pairs
    moved = q.copy()
    moved[0] += 0.5
    fk = client.compute_fk(_state(robot, moved), ["probe"])
    expected = robot.frame_pose(moved, "r_hand") @ np.linalg.inv(hand) @ over_desk
    assert np.allclose(_matrix(fk.poses[0].pose), expected, atol=1e-9)
    again = client.attach("probe", "r_hand", robot_state=_state(robot))
    assert again.error.code == _code("OBJECT_ALREADY_ATTACHED")
    detached = client.detach("probe", robot_state=_state(robot, moved))
    assert detached.error.code == _code("SUCCESS") and "probe" in detached.obstacle_names
    obstacle = next(o for o in client.get_scene().obstacles if o.name == "probe")
    assert np.allclose(_matrix(obstacle.pose), expected, atol=1e-6)
    assert "attached:" not in client.get_scene().scene_yaml
    assert client.remove_obstacle("probe").error.code == _code("SUCCESS")
    assert client.check_state_validity(_state(robot)).valid


def test_attach_errors_leave_the_scene_unchanged(client, robot):
    before = client.get_scene().scene_yaml
    assert client.attach("ghost", "r_hand", robot_state=_state(robot)).error.code == _code("INVALID_OBJECT_NAME")
    assert client.attach("box", "no_link", robot_state=_state(robot)).error.code == _code("INVALID_LINK_NAME")
    bad_touch = client.attach("box", "r_hand", touch_links=["nope"], robot_state=_state(robot))
    assert bad_touch.error.code == _code("INVALID_LINK_NAME")
    assert client.detach("box", robot_state=_state(robot)).error.code == _code("INVALID_OBJECT_NAME")
    assert client.get_scene().scene_yaml == before


def test_plan_motion_keeps_the_path_constraints(client, robot):
    from maru_planner.planning.constraints import OrientationConstraint, PathConstraints
    from maru_planner.ros.planning_client import plan_request
    from maru_planner.ros.planning_conversions import matrix_to_quaternion, trajectory_positions
    from maru_planner_interfaces.msg import PathConstraints as PathConstraintsMsg

    q = np.array(Q_FREE)
    upright = robot.frame_pose(q, "r_hand")[:3, :3]
    core = PathConstraints(OrientationConstraint("r_hand", upright, np.array([0.1, 0.1, math.pi])))
    indices = robot.group_joint_indices("right_arm")
    moved = q.copy()
    moved[indices] += (0.3, -0.2, 0.2, 0.0, 0.3, 0.2)
    goal = core.project(robot, moved, indices)
    assert goal is not None
    msg = PathConstraintsMsg(orientation_link="r_hand")
    o = msg.orientation
    o.x, o.y, o.z, o.w = matrix_to_quaternion(upright)
    msg.orientation_tolerance.x = msg.orientation_tolerance.y = 0.1
    msg.orientation_tolerance.z = math.pi
    request = plan_request({robot.joint_names[i]: float(goal[i]) for i in indices}, start=_state(robot),
                           group="right_arm", seed=1, time_budget=30.0)  # fmt: skip
    request.path_constraints = msg
    response = client.call(client.plan_client, request, 90.0)
    assert response.error.code == _code("SUCCESS"), response.error.message
    assert response.stats.planner_id == "CBiRRT"
    names, _times, positions = trajectory_positions(response.trajectory)
    for row in positions:
        q[robot.joint_indices(names)] = row
        assert core.violation(robot, q)[0] <= 1e-6
    request.planner_id = "PRM"
    assert client.call(client.plan_client, request, 60.0).error.code == _code("INVALID_PLANNER")
    request.planner_id = ""
    o.x, o.y, o.z, o.w = 0.0, 0.0, 0.0, 1.0  # a target the start is far from
    msg.orientation_tolerance.z = 0.1
    response = client.call(client.plan_client, request, 60.0)
    assert response.error.code == _code("START_STATE_VIOLATES_PATH_CONSTRAINTS"), response.error.message
