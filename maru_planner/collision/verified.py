"""Plan on the fast sphere checker, then verify the path on the exact model (and fall back if it fails).

:func:`plan_verified` is what "a sphere approximation for planning, verified on the exact model" means
in this package (see ``docs/fast_collision.md``):

1. ``planner.plan(request)`` with the planner's own checker (a :class:`SphereCollisionChecker`);
2. the returned path, with the joints outside the group at their start values, is re-checked with the
   exact :class:`~maru_planner.collision.CollisionChecker` at ``resolution`` (default: a quarter of the
   planner's motion resolution) by :func:`~maru_planner.collision.spheres.verify_path`;
3. if that finds a collision, the request is planned again in the time left with the motion resolution
   halved (the sphere checker with ``confirm=True`` answers like the exact model at every state it
   checks, so a failed verification can only mean an edge stepped over a thin obstacle), up to
   ``max_refinements`` times; a path that failed verification is never returned as a success.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from maru_planner.collision.spheres import PathVerification, verify_path


@dataclass
class VerifiedResult:
    """A planning result and how its verification on the exact model went."""

    result: object  # maru_planner.planning.MotionResult
    verification: PathVerification | None  # None when there was no path to verify
    verify_time: float = 0.0
    fallback_used: bool = False
    total_time: float = 0.0

    @property
    def success(self) -> bool:
        return bool(self.result.success and (self.verification is None or self.verification.valid))


def full_path(robot, request, result) -> np.ndarray:
    """The result's waypoints as full robot configurations (other joints at their start values)."""
    q = np.asarray(robot.neutral(), dtype=float).copy()
    start = request.start or {}
    q[robot.joint_indices(list(start))] = [float(v) for v in start.values()]
    idx = robot.joint_indices(list(result.joint_names))
    out = np.repeat(q[None], len(result.path), axis=0)
    out[:, idx] = np.asarray(result.path, dtype=float)
    return out


def plan_verified(planner, exact_checker, request, resolution: float | None = None, max_refinements: int = 2):
    """Plan with ``planner`` (fast checker), verify on ``exact_checker``; see the module doc."""
    from maru_planner.planning import MotionPlanner, PlanStatus

    t0 = time.monotonic()
    resolution = resolution or 0.25 * planner.config.resolution
    out = VerifiedResult(planner.plan(request), None)
    current, refinements = planner, 0
    while out.result.success:
        t1 = time.monotonic()
        out.verification = verify_path(exact_checker, full_path(planner.robot, request, out.result), resolution)
        out.verify_time += time.monotonic() - t1
        if out.verification.valid:
            break
        out.result.status = PlanStatus.PLANNING_FAILED
        out.result.message = (
            f"path failed verification on the exact model (segment {out.verification.first_invalid_segment})"
        )
        left = request.time_budget - (time.monotonic() - t0)
        if refinements >= max_refinements or left <= 0:
            break
        refinements += 1
        config = dataclasses.replace(current.config, resolution=0.5 * current.config.resolution)
        current = MotionPlanner(planner.robot, planner.checker, config)
        out.result = current.plan(dataclasses.replace(request, time_budget=left))
        out.fallback_used = True
    out.total_time = time.monotonic() - t0
    return out
