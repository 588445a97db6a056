"""Parameterize stage: the path timed by the request's method (:mod:`maru_planner.trajectory`), its blended corners
checked -- with a certifier, proven clear by the request's safety margin -- and the request answered SUCCESS.

Blends still unchecked at the budget's end become stops, so a tight budget gets a slower trajectory rather than a
timeout; a path whose post-processing overran the budget is a timeout all the same.
"""

from __future__ import annotations

import time

import numpy as np

from maru_planner import errors
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.space import full_configurations
from maru_planner.planning.types import MotionResult, PlanStatus
from maru_planner.trajectory import (
    CERTIFY_STEP,
    CurveFree,
    Limits,
    TimingReport,
    Trajectory,
    WatchedCurve,
    certified_curve,
    path_length,
    smoothness,
)
from maru_planner.trajectory import parameterize as time_parameterize

# rad: chords of a certified blend. Their count drives the blends' certification; the chord deviation margin
# grows with the step squared. On 30 MotionBenchMaker plans 0.05 -> 0.1 rad took time parameterisation from
# 21.5 to 14.8 ms median with 215 of 217 corners still blended (216 before); 0.2 rad stopped at 8 corners.
CERTIFIED_CHORD_STEP = 0.1


def parameterize(problem: PlanningProblem, result: MotionResult) -> None:
    """``result.trajectory`` from ``result.path``; SUCCESS, or PlanningTimedOut past the budget."""
    assert result.path is not None
    trajectory = set_path(problem, result, result.path, problem.deadline)
    if time.monotonic() > problem.deadline:
        raise errors.PlanningTimedOut(
            f"a path was found but the {problem.budget:.3g} s budget ran out during post-processing", source="planner"
        )
    stats = result.stats
    result.status = PlanStatus.SUCCESS
    result.message = (
        f"{problem.planner_id}: {len(result.path)} waypoints, length {stats.path_length:.3f} rad, "
        f"trajectory {trajectory.duration:.2f} s ({stats.time_parameterization})"
    )


def set_path(problem: PlanningProblem, result: MotionResult, path: np.ndarray, deadline: float) -> Trajectory:
    """Make ``path`` (group configurations) the result's path, with its trajectory (returned) and statistics."""
    stats = result.stats
    t_par = time.monotonic()
    result.trajectory, report = _time(problem, path, deadline)
    stats.time_parameterization = report.method
    certifier = problem.context.certifier
    result.corner_blends = report.corner_blends if certifier is not None else None
    result.curve_proof = report if report.curve_certified else None  # only a certifier's check proves pieces
    stats.min_clearance = min(stats.min_clearance, report.min_clearance)  # the blends' (the path's: certify)
    stats.parameterize_time += time.monotonic() - t_par
    result.path = path
    stats.waypoints = len(path)
    stats.path_length = path_length(path)
    stats.smoothness = smoothness(path)
    return result.trajectory


def _time(problem: PlanningProblem, path: np.ndarray, deadline: float) -> tuple[Trajectory, TimingReport]:
    request, config, robot, indices = problem.request, problem.config, problem.robot, problem.indices
    curve_free, certify_step = _curve_check(problem, deadline)
    limits = Limits.scaled(
        np.asarray(robot.velocity_limits)[indices],
        np.asarray(robot.acceleration_limits)[indices],
        float(request.velocity_scaling),
        float(request.acceleration_scaling),
        float(request.jerk_scaling),
    )
    return time_parameterize(
        path,
        problem.joint_names,
        limits,
        request.time_parameterization or config.time_parameterization,
        curve_free=curve_free,
        max_deviation=config.blend_deviation,
        dt=config.trajectory_dt,
        max_points=config.max_trajectory_points,
        deadline=deadline,
        certify_step=certify_step,
        sample_deadline=deadline,
    )


def _curve_check(problem: PlanningProblem, deadline: float) -> tuple[CurveFree, float]:
    """How blended corners are checked, and the joint step of their samples.

    With a certifier, like the path: proven clear by the request's safety margin, toppra's parabolic blends as they
    are, sampled curves (Ruckig's) continuously along chords :data:`CERTIFIED_CHORD_STEP` apart, the margin grown by
    how far the curve leaves them. Otherwise the exact checker at the states alone, ``CERTIFY_STEP`` apart.
    """
    context, start_full, indices = problem.context, problem.start_full, problem.indices
    if context.certifier is not None:
        curve_free = certified_curve(context.certifier, start_full, indices, deadline, problem.margin)
        step = CERTIFIED_CHORD_STEP
    else:
        checker = context.exact_checker or context.checker

        def curve_free(states: np.ndarray, _chord_deviation: np.ndarray) -> bool:
            return checker.first_invalid(full_configurations(start_full, indices, states)) < 0

        step = CERTIFY_STEP
    return WatchedCurve(curve_free, problem.monitor.check), step
