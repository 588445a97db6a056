"""Time-dense stage (paths with path constraints): a trajectory that stays within
:data:`~maru_planner.planning.cartesian.BLEND_DEVIATION` rad of the path's polyline (so it keeps the constraints
the path keeps), its blends certified by the margin the path was proven with; the request answered SUCCESS."""

from __future__ import annotations

import time

import numpy as np

from maru_planner.planning.cartesian import time_dense_path
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.types import MotionResult, PlanStatus
from maru_planner.trajectory import path_length, smoothness


def time_dense(problem: PlanningProblem, result: MotionResult) -> None:
    assert result.path is not None
    stats, request, config = result.stats, problem.request, problem.config
    problem.monitor.report("parameterize", best_cost=path_length(result.path))
    t_par = time.monotonic()
    method = request.time_parameterization or config.time_parameterization
    scalings = (float(request.velocity_scaling), float(request.acceleration_scaling))
    result.trajectory = time_dense_path(problem.robot, config, problem.context.certifier, problem.full(result.path),
                                        np.asarray(problem.indices), method, scalings, problem.deadline,
                                        problem.margin_kept)  # fmt: skip
    stats.parameterize_time = time.monotonic() - t_par
    path = result.path
    stats.waypoints, stats.path_length, stats.smoothness = len(path), path_length(path), smoothness(path)
    result.status = PlanStatus.SUCCESS
    result.message = (
        f"{problem.planner_id}: {len(path)} waypoints on the path constraints, length {stats.path_length:.3f} rad"
    )
