"""Verify stage (a plan on the sphere model without certification): the path re-checked on the exact model every
``config.verify_step`` rad; while it fails, the request is re-planned at half the motion resolution, up to
``config.max_refinements`` times in the time left, and never returned as a success."""

from __future__ import annotations

import time

from maru_planner import errors
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.types import MotionResult, set_failure


def verify(problem: PlanningProblem, result: MotionResult) -> MotionResult:
    """The verified result (stats.verified, verify_time, replans), a re-planned one, or a failure without a path."""
    # lazy: the sphere module loads numba, which exact-only callers never need
    from maru_planner.collision.spheres import verify_path

    context, config = problem.context, problem.config
    assert problem.replan is not None
    resolution, verify_time, replans = config.resolution, 0.0, 0
    while result.success:
        problem.monitor.report("certify")
        t_ver = time.monotonic()
        assert result.path is not None
        path = problem.full(result.path)
        result.verification = verify_path(context.exact_checker, path, config.verify_step)
        verify_time += time.monotonic() - t_ver
        if result.verification.valid:
            result.stats.verified = True
            break
        segment = result.verification.first_invalid_segment
        out_of_time = time.monotonic() >= problem.deadline
        if replans >= config.max_refinements or out_of_time:
            set_failure(result, errors.PlanningFailed(
                f"path failed verification on the exact model (segment {segment}) after {replans} re-plan(s)"
                + (", time budget spent" if out_of_time else ""),
                source="planner",
            ))  # fmt: skip
            result.path, result.trajectory = None, None
            break
        replans += 1
        resolution *= 0.5
        result = problem.replan(resolution)
    result.stats.verify_time, result.stats.replans = verify_time, replans
    return result
