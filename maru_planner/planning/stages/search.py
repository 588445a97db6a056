"""Search stage: the problem's planner, ``request.attempts`` times until one finds a path, in the search's share
of the budget (``config.postprocess_reserve`` of the time left is kept for the stages after it)."""

from __future__ import annotations

import time

import numpy as np

from maru_planner import errors
from maru_planner.planning.planners.ompl_search import search_tree
from maru_planner.planning.planners.registry import ArmPlannerSpec, get_spec, merged_params
from maru_planner.planning.planners.roadmap_search import search_roadmap
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.types import MotionResult
from maru_planner.trajectory.metrics import path_length


def search(problem: PlanningProblem, result: MotionResult) -> None:
    """``result.path`` = the raw path found (group configurations); counts in ``result.stats``."""
    stats, checker = result.stats, problem.checker
    checks0 = checker.check_count
    problem.monitor.report("search")
    try:
        raw = _search(problem, get_spec(problem.planner_id), result)
    finally:
        stats.collision_checks = int(checker.check_count - checks0)
    stats.raw_waypoints = len(raw)
    stats.raw_path_length = path_length(raw)
    result.path = raw


def _search(problem: PlanningProblem, spec: ArmPlannerSpec, result: MotionResult) -> np.ndarray:
    stats = result.stats
    start, goal = problem.start, problem.goal
    if np.allclose(start, goal, atol=1e-12, rtol=0):
        stats.attempts_used = 0
        return np.vstack([start, goal])
    reserve = problem.config.postprocess_reserve * max(0.0, problem.deadline - time.monotonic())
    search_deadline = problem.deadline - reserve
    params = merged_params(spec.id, problem.config.planner_params.get(spec.id))
    planner_search = spec.search or (search_roadmap if spec.has("roadmap") else search_tree)
    failure = None
    for attempt in range(int(problem.request.attempts)):
        if search_deadline <= time.monotonic():
            break
        stats.attempts_used = attempt + 1
        t_solve = time.monotonic()
        build_before = stats.roadmap_build_time
        path, failure = planner_search(problem, params, problem.seed + attempt, search_deadline, stats)
        # roadmap planners: query time only; the roadmap build is reported apart (roadmap_build_time)
        stats.solve_time += time.monotonic() - t_solve - (stats.roadmap_build_time - build_before)
        problem.monitor.report("search", nodes=stats.nodes)  # raises if the search ended by a cancel
        if path is not None:
            return path
    if failure is None or time.monotonic() >= search_deadline:
        raise errors.PlanningTimedOut(
            f"{spec.id} found no path within the time budget ({stats.attempts_used} attempt(s), {stats.nodes} nodes)",
            source="planner",
        )
    raise errors.PlanningFailed(failure, source="planner")
