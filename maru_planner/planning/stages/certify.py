"""Certify stage: the path proven collision-free on the exact model by the request's safety margin
(``docs/certification.md``); a failing segment re-planned locally (:mod:`.repair`) in the time left, else the
request fails with its path dropped."""

from __future__ import annotations

import time
from typing import Any

from maru_planner import errors
from maru_planner.planning.checkers import is_sphere_checker
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.stages.parameterize import set_path
from maru_planner.planning.stages.repair import RepairPlanner
from maru_planner.planning.types import MotionResult, set_failure


def certify(problem: PlanningProblem, result: MotionResult) -> MotionResult:
    """``result`` certified (stats.certified, certify_time, min_clearance, repairs), or failed without a path."""
    if not result.success:
        return result
    try:
        _certify(problem, result)
    except Exception as exc:  # a typed error, or a bug in certification: reported, the planner keeps serving
        set_failure(result, exc)
        result.path, result.trajectory = None, None
    return result


def _certify(problem: PlanningProblem, result: MotionResult) -> None:
    # lazy: certification loads numba (batched kinematics); planners on toy checkers never need it
    from maru_planner.collision.certify import Certificate, certify_and_repair

    stats, context = result.stats, problem.context
    assert result.path is not None and context.certifier is not None
    problem.monitor.report("certify")
    sphere_plan = is_sphere_checker(context.checker)
    proof = result.curve_proof
    if proof is not None:  # every straight part was proven with the blends (parameterize): nothing left
        stats.certified, stats.certify_time = True, proof.certify_time  # that proof's time, also in parameterize_time
        if sphere_plan:
            certificate = Certificate(valid=True, margin=problem.margin, checks=proof.certify_checks,
                                      seconds=proof.certify_time)  # fmt: skip
            record_verification(result, certificate, 0)
        return
    certify_deadline = time.monotonic() + problem.config.certify_timeout
    repaired = certify_and_repair(
        context.certifier,
        problem.full(result.path),
        RepairPlanner(problem, stats.seed or 0),
        problem.deadline,
        margin=problem.margin,
        max_repairs=problem.config.max_refinements,
        certify_deadline=certify_deadline,
        corner_blends=result.corner_blends,
    )
    problem.monitor.check()  # a repair search ended by a cancel looks like a failed repair
    certificate = repaired.certificate
    stats.certified, stats.repairs = repaired.path is not None, repaired.repairs
    stats.certify_time = certificate.seconds
    stats.min_clearance = min(stats.min_clearance, certificate.min_clearance)  # and the blends' (parameterize)
    if sphere_plan:
        record_verification(result, certificate, repaired.repairs)
    if repaired.path is None:
        raise errors.PlanningFailed(
            f"path failed verification on the exact model: segment {certificate.first_failing_segment} "
            f"not certified ({certificate.reason}) after {repaired.repairs} repair(s)",
            source="planner",
        )
    if repaired.repairs:  # timing the repaired path may take as long as the certification was allowed to
        set_path(problem, result, repaired.path[:, problem.indices], certify_deadline)


def record_verification(result: MotionResult, certificate: Any, repairs: int) -> None:
    """A sphere plan's exact re-check is its certification: the verification fields report it."""
    from maru_planner.collision.spheres import PathVerification  # lazy: numba; only sphere plans get here

    stats = result.stats
    stats.verified, stats.verify_time, stats.replans = stats.certified, certificate.seconds, repairs
    failing = certificate.first_failing_segment
    result.verification = PathVerification(stats.certified, failing, certificate.checks)
