"""Plan on the fast sphere checker, verified on the exact model: a thin wrapper over ``MotionPlanner``.

The verification itself lives in the planning facade: ``MotionPlanner.plan`` on a
:class:`~maru_planner.collision.SphereCollisionChecker` re-checks the final path on the exact model at
``config.verify_step`` and re-plans at half the motion resolution while it fails, up to
``config.max_refinements`` times (see ``docs/fast_collision.md``). :func:`plan_verified` keeps the older
call shape (an explicit exact checker, resolution and refinements) and returns a :class:`VerifiedResult`.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from maru_planner.collision.spheres import PathVerification
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.space import full_configurations
from maru_planner.planning.types import MotionRequest, MotionResult


@dataclass
class VerifiedResult:
    """A planning result and how its verification on the exact model went."""

    result: MotionResult
    verification: PathVerification | None  # None when there was no path to verify
    verify_time: float = 0.0
    fallback_used: bool = False  # at least one re-plan after a failed verification
    total_time: float = 0.0

    @property
    def success(self) -> bool:
        return bool(self.result.success and (self.verification is None or self.verification.valid))


def full_path(robot, request: MotionRequest, result: MotionResult) -> np.ndarray:
    """The result's waypoints as full robot configurations (other joints at their start values)."""
    q = np.asarray(robot.neutral(), dtype=float).copy()
    start = request.start or {}
    q[robot.joint_indices(list(start))] = [float(v) for v in start.values()]
    return full_configurations(q, robot.joint_indices(list(result.joint_names)), np.asarray(result.path, dtype=float))


def plan_verified(
    planner: MotionPlanner,
    exact_checker,
    request: MotionRequest,
    resolution: float | None = None,
    max_refinements: int = 2,
) -> VerifiedResult:
    """``planner``'s plan of ``request``, verified on ``exact_checker`` every ``resolution`` rad."""
    t0 = time.monotonic()
    config = dataclasses.replace(planner.config, verify_resolution=resolution, max_refinements=max_refinements)
    result = MotionPlanner(planner.robot, planner.checker, config, exact_checker=exact_checker).plan(request)
    stats = result.stats
    return VerifiedResult(result, result.verification, stats.verify_time, stats.replans > 0, time.monotonic() - t0)
