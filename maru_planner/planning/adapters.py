"""Request adapters: a :class:`MotionRequest` checked and resolved into a :class:`PlanningProblem`.

The chain in front of the search (MoveIt's planning request adapters): request fields -> planner -> group ->
start -> goal (joints, IK of poses, or a goal region) -> path constraints -> collision checks of both ends ->
the checker the search plans on. Each step raises a typed error with a one-line message.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.constraints import PathConstraints
from maru_planner.planning.context import PlanningContext
from maru_planner.planning.goals import goal_configuration
from maru_planner.planning.planners.registry import PLANNERS, ArmPlannerSpec, get_spec
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.requests import check_free, check_request, safety_margin, start_configuration
from maru_planner.planning.types import MotionRequest, MotionResult

PATH_CONSTRAINTS = "path_constraints"  # the capability a planner needs for a request with path constraints


def resolve_spec(request: MotionRequest, config: PlannerConfig) -> ArmPlannerSpec:
    """The planner of ``request``: its id, else the configuration's default, else (with path constraints) the
    first registered planner able to keep them; InvalidPlanner for an unknown id or one that cannot."""
    constraints = getattr(request, "path_constraints", None)
    if constraints is None or constraints.empty:
        return get_spec(request.planner_id or config.default_planner)
    if not request.planner_id:
        return next(spec for spec in PLANNERS.values() if spec.has(PATH_CONSTRAINTS))
    spec = get_spec(request.planner_id)
    if not spec.has(PATH_CONSTRAINTS):
        able = next(s.id for s in PLANNERS.values() if s.has(PATH_CONSTRAINTS))
        raise errors.InvalidPlanner(
            f"planner {request.planner_id!r} does not support path constraints; use {able} (or leave it empty)"
        )
    return spec


def build_problem(context: PlanningContext, request: MotionRequest, result: MotionResult, monitor: PlanMonitor,
                  t0: float, resolution: float) -> PlanningProblem:  # fmt: skip
    """``request`` checked and resolved into a problem (module doc); fills ``result``'s joint names and stats."""
    stats, robot = result.stats, context.robot
    spec = resolve_spec(request, context.config)
    stats.planner_id = spec.id
    budget, seed = check_request(request, context.config)
    stats.seed = seed
    monitor.report("validation")
    constraints = getattr(request, "path_constraints", None) or PathConstraints()
    constraints.check_links(robot)
    indices = sorted(robot.group_joint_indices(request.group))
    names = [robot.joint_names[i] for i in indices]
    result.joint_names = names
    start_full = start_configuration(robot, request.start, indices, request.group)
    goal_full = _goal(context, request, start_full, indices, t0 + budget, stats, monitor)
    t_val = time.monotonic()
    _check_ends(robot, constraints, start_full, goal_full)
    check_free(context.checker, start_full, errors.StartInCollision, "start")
    check_free(context.checker, goal_full, errors.GoalInCollision, "goal")
    stats.validation_time = time.monotonic() - t_val
    margin = safety_margin(request, context.config)
    checker = context.checker if spec.has(PATH_CONSTRAINTS) else context.search_checker(margin, start_full, goal_full)
    context.last_search_checker = checker
    setup = context.group_setup(checker, names, indices, start_full, resolution)
    return PlanningProblem(request, context, spec.id, monitor, t0, budget, seed, resolution, indices, names, start_full,
                           goal_full, constraints, checker, setup, np.random.default_rng(seed), margin)  # fmt: skip


def _goal(context: PlanningContext, request: MotionRequest, start_full: np.ndarray, indices: list[int],
          deadline: float, stats: Any, monitor: PlanMonitor) -> np.ndarray:  # fmt: skip
    if not request.goal_poses:
        return goal_configuration(context.robot, context.checker, request, start_full, indices, deadline)
    monitor.report("ik")
    t_ik = time.monotonic()
    goal = goal_configuration(context.robot, context.checker, request, start_full, indices, deadline)
    stats.ik_time = time.monotonic() - t_ik
    monitor.report("validation")
    return goal


def _check_ends(robot: Any, constraints: PathConstraints, start: np.ndarray, goal: np.ndarray) -> None:
    """Both ends inside the path constraints (else they cannot hold along the motion)."""
    if constraints.empty:
        return
    for q, what, error_cls in (
        (start, "start", errors.StartViolatesConstraints),
        (goal, "goal", errors.InvalidRequest),
    ):
        orientation, position = constraints.violation(robot, q)
        if orientation > 0 or position > 0:
            raise error_cls(
                f"the {what} state violates the path constraints (orientation by {orientation:.3f} rad, "
                f"position by {position:.3f} m), so they cannot hold along the motion"
            )
