"""Simplify stage: random shortcuts on the search's own edge check (group, checker, motion resolution), so the
shorter path is as free as the raw one; with path constraints every shortcut keeps them too."""

from __future__ import annotations

import time

import numpy as np

from maru_planner.planning.checkers import is_compiled_sphere_checker
from maru_planner.planning.planners.cbirrt import constrained_edge_valid
from maru_planner.planning.postprocess import shortcut
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.types import MotionResult
from maru_planner.trajectory.metrics import path_length

CONSTRAINED_SHARE = 0.9  # of the budget: shortcutting a constrained path ends by then (proof and timing follow)
CONSTRAINED_TRIES = 50  # failed shortcuts in a row that end a constrained path's simplification


def simplify(problem: PlanningProblem, result: MotionResult) -> None:
    """``result.path`` shortcut when the request asks for it (``request.simplify``)."""
    assert result.path is not None
    raw = result.path
    problem.monitor.report("simplify", best_cost=result.stats.raw_path_length)
    if problem.request.simplify:
        t_simp, checks0 = time.monotonic(), problem.checker.check_count
        try:
            result.path = _constrained(problem, raw) if problem.constrained else _shortcut(problem, raw)
        finally:
            result.stats.collision_checks += int(problem.checker.check_count - checks0)
        result.stats.simplify_time = time.monotonic() - t_simp
    problem.monitor.report("parameterize", best_cost=path_length(result.path))


def _shortcut(problem: PlanningProblem, raw: np.ndarray) -> np.ndarray:
    if len(raw) <= 2:
        return raw
    edges, monitor = problem.edges, problem.monitor
    max_tries = problem.config.simplify_max_tries
    if is_compiled_sphere_checker(edges.checker):
        # lazy: numba is loaded already (a sphere checker exists); exact-only callers never need it
        from maru_planner.planning.planners.compiled_shortcut import shortcut as compiled_shortcut

        return compiled_shortcut(raw, edges, problem.seed, problem.deadline, max_tries, monitor.check)

    def edge_valid(qa: np.ndarray, qb: np.ndarray) -> bool:
        monitor.check()
        return edges.edge_valid(qa, qb)

    path, _checks = shortcut(raw, edge_valid, problem.rng, problem.deadline, max_tries)
    return path


def _constrained(problem: PlanningProblem, raw: np.ndarray) -> np.ndarray:
    deadline = problem.t0 + CONSTRAINED_SHARE * problem.budget
    path, _checks = shortcut(raw, constrained_edge_valid(problem), problem.rng, deadline, CONSTRAINED_TRIES)
    return path
