"""Prove stage (paths a repair could not re-plan: with path constraints): the path certified collision-free on the
exact model, no repair, by the request's margin lowered to half the ends' clearance when they are closer."""

from __future__ import annotations

import time

from maru_planner import errors
from maru_planner.planning.cartesian import end_margin
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.types import MotionResult


def prove(problem: PlanningProblem, result: MotionResult) -> None:
    """``problem.margin_kept`` = the margin proven (0 without a certifier); PlanningFailed if the proof fails."""
    certifier, stats = problem.context.certifier, result.stats
    if certifier is None:
        problem.margin_kept = 0.0
        return
    assert result.path is not None
    problem.monitor.report("certify")
    full = problem.full(result.path)
    margin = end_margin(problem.context, problem.margin, full[0], full[-1])
    deadline = max(problem.deadline, time.monotonic() + problem.config.certify_timeout)
    certificate = certifier.certify_path(full, deadline, margin=margin)
    stats.certify_time, stats.min_clearance = certificate.seconds, certificate.min_clearance
    if not certificate.valid:
        raise errors.PlanningFailed(
            f"{problem.planner_id} path not certified collision-free: segment {certificate.first_failing_segment} "
            f"({certificate.reason})", source="planner",
        )  # fmt: skip
    stats.certified = True
    problem.margin_kept = margin
