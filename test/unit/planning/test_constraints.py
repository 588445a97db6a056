"""Path constraints: projection, CBiRRT keeping a link upright / in a box all along, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.config import COLLISION_MODELS
from maru_planner.planning.constraints import OrientationConstraint, PathConstraints, PositionConstraint
from maru_planner.planning.dual_arm import DUAL_CARRY, relative_pose_error
from maru_planner.robot import RobotModel
from maru_planner.scene import Scene

LINK = "panda_hand_tcp"


@pytest.fixture(scope="module")
def panda():
    robot = RobotModel.from_profile("panda")
    return robot, robot.named_state("default"), robot.group_joint_indices("arm")


def _upright(robot, q) -> PathConstraints:
    """The hand's orientation at ``q`` kept within 0.1 rad about x and y, free about z."""
    target = robot.frame_pose(q, LINK)[:3, :3]
    return PathConstraints(OrientationConstraint(LINK, target, np.array([0.1, 0.1, math.pi])))


def _tilting_goal(robot, q0, idx, constraints) -> np.ndarray:
    """A goal on the constraints whose straight joint-space line leaves them (so planning must work for it)."""
    rng = np.random.default_rng(0)
    for _ in range(200):
        q = q0.copy()
        q[idx] += rng.uniform(-1.0, 1.0, len(idx))
        goal = constraints.project(robot, np.clip(q, robot.lower_limits, robot.upper_limits), idx)
        if goal is None:
            continue
        line = [q0 + t * (goal - q0) for t in np.linspace(0, 1, 21)]
        if max(constraints.violation(robot, q)[0] for q in line) > 0.1:
            return goal
    raise AssertionError("no tilting goal found")


def _violation_along(robot, q0, idx, trajectory, constraints) -> tuple[float, float]:
    q, worst = q0.copy(), np.zeros(2)
    for row in trajectory.positions:
        q[idx] = row
        worst = np.maximum(worst, constraints.violation(robot, q))
    return float(worst[0]), float(worst[1])


def test_projection_lands_on_the_constraints(panda):
    robot, q0, idx = panda
    constraints = _upright(robot, q0)
    rng = np.random.default_rng(3)
    landed = 0
    for _ in range(20):
        q = robot.random_configuration(rng)
        projected = constraints.project(robot, q, idx)
        if projected is not None:
            landed += 1
            assert constraints.satisfied(robot, projected)
            assert np.all(projected >= robot.lower_limits) and np.all(projected <= robot.upper_limits)
    assert landed >= 10


@pytest.mark.parametrize("model", COLLISION_MODELS)
def test_cbirrt_keeps_the_hand_upright_all_along(panda, model):
    robot, q0, idx = panda
    constraints = _upright(robot, q0)
    goal = _tilting_goal(robot, q0, idx, constraints)
    planner = MotionPlanner.from_scene(robot, Scene(), PlannerConfig(collision_model=model))
    start = dict(zip(robot.joint_names, q0.tolist(), strict=True))
    goal_joints = {robot.joint_names[i]: float(goal[i]) for i in idx}
    result = planner.plan(
        MotionRequest("arm", start=start, goal_joints=goal_joints, seed=2, time_budget=30, path_constraints=constraints)
    )
    assert result.status is PlanStatus.SUCCESS, result.message
    assert result.stats.planner_id == "CBiRRT" and result.stats.certified
    assert result.stats.collision_model == model  # the checker CBiRRT searched on
    orientation, _ = _violation_along(robot, q0, idx, result.trajectory, constraints)
    assert orientation <= 1e-6
    assert np.allclose(result.trajectory.positions[-1], goal[idx], atol=1e-6)


def test_cbirrt_keeps_the_hand_in_a_box(panda):
    robot, q0, idx = panda
    hand = robot.frame_pose(q0, LINK)
    box = hand.copy()
    box[:3, 3] += (0.0, 0.15, 0.0)
    constraints = PathConstraints(position=PositionConstraint(LINK, box, np.array([0.3, 0.5, 0.1])))
    q = q0.copy()
    q[idx[0]] += 0.6
    goal = constraints.project(robot, q, idx)
    assert goal is not None
    result = MotionPlanner.from_scene(robot, Scene()).plan(MotionRequest(
        "arm", start=dict(zip(robot.joint_names, q0.tolist(), strict=True)),
        goal_joints={robot.joint_names[i]: float(goal[i]) for i in idx}, seed=1, time_budget=30,
        path_constraints=constraints,
    ))  # fmt: skip
    assert result.success, result.message
    assert _violation_along(robot, q0, idx, result.trajectory, constraints)[1] <= 1e-6


def test_cbirrt_certifies_by_the_requests_safety_margin(panda):
    robot, q0, idx = panda
    constraints = _upright(robot, q0)
    goal = _tilting_goal(robot, q0, idx, constraints)
    planner = MotionPlanner.from_scene(robot, Scene())
    margins: list[float] = []
    certify_path = planner.certifier.certify_path

    def recording(path, deadline, margin=None, **kwargs):
        margins.append(margin)
        return certify_path(path, deadline, margin=margin, **kwargs)

    planner.certifier.certify_path = recording
    result = planner.plan(MotionRequest(
        "arm", start=dict(zip(robot.joint_names, q0.tolist(), strict=True)),
        goal_joints={robot.joint_names[i]: float(goal[i]) for i in idx}, seed=2, time_budget=30,
        path_constraints=constraints, safety_margin=0.003,
    ))  # fmt: skip
    assert result.success, result.message
    ends = min(planner.certifier.clearance(q0), planner.certifier.clearance(goal))
    assert margins[0] == pytest.approx(min(0.003, 0.5 * ends)) and margins[0] < planner.config.safety_margin


def test_constraint_impossible_at_the_start_unknown_link_and_unsupported_planner(panda):
    robot, q0, idx = panda
    tilted = robot.frame_pose(q0, LINK)[:3, :3] @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    away = PathConstraints(OrientationConstraint(LINK, tilted, np.array([0.1, 0.1, 0.1])))
    start = dict(zip(robot.joint_names, q0.tolist(), strict=True))
    goal = {robot.joint_names[i]: float(q0[i]) for i in idx}
    goal["panda_joint1"] += 0.1
    planner = MotionPlanner.from_scene(robot, Scene())

    def plan(constraints, planner_id=""):
        return planner.plan(MotionRequest("arm", start=start, goal_joints=goal, planner_id=planner_id,
                                          path_constraints=constraints))  # fmt: skip

    impossible = plan(away)
    assert impossible.status is PlanStatus.START_VIOLATES_CONSTRAINTS and "start" in impossible.message
    unknown = PathConstraints(OrientationConstraint("no_link", np.eye(3), np.ones(3)))
    assert plan(unknown).status is PlanStatus.INVALID_LINK
    assert plan(_upright(robot, q0), "PRM").status is PlanStatus.INVALID_PLANNER
    with pytest.raises(ValueError, match="tolerance"):
        OrientationConstraint(LINK, np.eye(3), np.array([0.1, -1.0, 0.1]))


def test_dual_arm_carry_keeps_the_hands_relative_pose():
    robot = RobotModel.maru1()
    result = MotionPlanner.from_scene(robot, DUAL_CARRY.scene()).plan(DUAL_CARRY.request(robot, seed=1))
    assert result.success and result.stats.certified, result.message
    assert abs(result.trajectory.positions[-1, 0] - result.trajectory.positions[0, 0]) == pytest.approx(1.0)
    translation, rotation = relative_pose_error(robot, DUAL_CARRY, result.trajectory.positions)
    # per-component tolerances of 1 mm and 0.01 rad bound the norms by sqrt(3) times that
    assert translation.max() <= math.sqrt(3) * 1e-3 and rotation.max() <= math.sqrt(3) * 1e-2
    straight = np.linspace(DUAL_CARRY.start, DUAL_CARRY.goal, 21)
    assert relative_pose_error(robot, DUAL_CARRY, straight)[0].max() > 2e-3  # planning was needed


def test_goal_region_lands_inside_the_pose_tolerances(panda):
    robot, q0, idx = panda
    target = robot.frame_pose(q0, LINK).copy()
    target[:3, 3] += (0.1, 0.15, -0.1)
    region = PathConstraints(
        OrientationConstraint(LINK, target[:3, :3], np.array([0.05, 0.05, math.pi])),
        PositionConstraint(LINK, target, np.array([0.02, 0.02, 0.02])),
    )
    start = dict(zip(robot.joint_names, q0.tolist(), strict=True))
    planner = MotionPlanner.from_scene(robot, Scene())
    result = planner.plan(MotionRequest("arm", start=start, goal_region=region, seed=4, planner_id="RRTConnect"))
    assert result.success, result.message
    q = q0.copy()
    q[idx] = result.trajectory.positions[-1]
    assert region.satisfied(robot, q)
    away = np.eye(4)
    away[:3, 3] = (3.0, 0.0, 0.5)  # out of the arm's reach
    far = PathConstraints(position=PositionConstraint(LINK, away, np.full(3, 0.01)))
    unreachable = planner.plan(MotionRequest("arm", start=start, goal_region=far, time_budget=1.0))
    assert unreachable.status is PlanStatus.NO_IK_SOLUTION


def test_cbirrt_is_registered_and_a_cancel_stops_its_search(panda, monkeypatch):
    """CBiRRT is in the planner registry like every planner (its parameters with ranges, the path_constraints
    capability) and its search loop ends at a cancel arriving mid-search."""
    from maru_planner.errors import PlanningCancelled
    from maru_planner.monitor import PlanMonitor
    from maru_planner.planning import PLANNERS
    from maru_planner.planning.planners import cbirrt

    spec = PLANNERS["CBiRRT"]
    assert spec.has("path_constraints") and spec.search is cbirrt.search and set(spec.params) == {"step", "inset"}
    robot, q0, idx = panda
    constraints = _upright(robot, q0)
    goal = _tilting_goal(robot, q0, idx, constraints)
    monitor, extend = PlanMonitor(), cbirrt._Extender.__call__
    extensions = []

    def cancelled_while_extending(self, tree, target):
        extensions.append(target)
        monitor.cancel()  # as a client's cancel would, from its own thread, while the trees grow
        return extend(self, tree, target)

    monkeypatch.setattr(cbirrt._Extender, "__call__", cancelled_while_extending)
    request = MotionRequest("arm", start=dict(zip(robot.joint_names, q0.tolist(), strict=True)),
                            goal_joints={robot.joint_names[i]: float(goal[i]) for i in idx}, seed=2, time_budget=600,
                            path_constraints=constraints)  # fmt: skip
    result = MotionPlanner.from_scene(robot, Scene()).plan(request, monitor)
    assert isinstance(result.error, PlanningCancelled), result.message
    assert result.message == "cancelled during search" and len(extensions) <= 2
