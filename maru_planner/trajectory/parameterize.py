"""Time parameterisation of a certified joint-space path: ``toppra`` | ``ruckig`` | ``trapezoid``.

``trapezoid`` (:mod:`~maru_planner.trajectory.trapezoid`) stops at every waypoint. The other two first replace each
corner by a parabolic blend (:mod:`~maru_planner.trajectory.blends`) at most the requested deviation from it, every
blend re-checked by the caller's ``curve_free`` (:mod:`~maru_planner.trajectory.curves`,
:mod:`~maru_planner.trajectory.corners`); a corner whose blend cannot be certified stops. ``toppra``
(:mod:`~maru_planner.trajectory.toppra`) is time-optimal under the velocity and acceleration limits, ``ruckig``
(:mod:`~maru_planner.trajectory.ruckig`) jerk-limited through toppra's speeds at the blend boundaries.

Every trajectory is sampled with at most ``max_points`` points: the sample period grows past
``dt`` when the duration would need more (:mod:`~maru_planner.trajectory.sampling`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from maru_planner import errors
from maru_planner.trajectory.blends import distinct
from maru_planner.trajectory.curves import CERTIFY_STEP, Check, CurveFree, certified_clearance
from maru_planner.trajectory.limits import Limits, check_method
from maru_planner.trajectory.report import ParameterizationFailed, TimingReport
from maru_planner.trajectory.ruckig import ruckig_sections
from maru_planner.trajectory.sampling import sample
from maru_planner.trajectory.toppra import toppra_sections
from maru_planner.trajectory.trajectory import Trajectory
from maru_planner.trajectory.trapezoid import trapezoid_trajectory

__all__ = ["TimingReport", "parameterize"]


def parameterize(
    path: np.ndarray,
    joint_names: Sequence[str],
    limits: Limits,
    method: str,
    *,
    curve_free: CurveFree,
    max_deviation: float,
    dt: float = 0.05,
    max_points: int = 10_000,
    deadline: float | None = None,
    certify_step: float = CERTIFY_STEP,
    sample_deadline: float | None = None,
) -> tuple[Trajectory, TimingReport]:
    """Trajectory through ``path`` (rows: group configurations) by ``method`` (module doc).

    ``curve_free(Q, deviation)`` is True when the curve through the rows of ``Q`` (at most
    ``certify_step`` apart in every joint), which leaves the straight chords between consecutive rows
    by at most ``deviation[j]`` in joint j, is collision-free; it re-checks blends. ``max_deviation``
    (rad) bounds the distance of the blended curve from each corner. After ``deadline``
    (``time.monotonic()``) no more blends are checked: the corners left stop. Sampling the
    sections raises PlanningTimedOut once ``sample_deadline`` has passed (a caller's hard budget).
    """
    check_method(method)
    if not (math.isfinite(max_deviation) and max_deviation >= 0.0):
        raise errors.InvalidRequest(f"blend deviation must be a finite number >= 0 rad, got {max_deviation}")
    if max_points < 2:
        raise errors.InvalidRequest(f"max_points must be >= 2, got {max_points}")
    waypoints = distinct(np.asarray(path, float))
    if method == "trapezoid" or len(waypoints) < 2:
        return trapezoid_trajectory(waypoints, joint_names, limits, dt, max_points), TimingReport("trapezoid")
    if method == "toppra" and len(waypoints) == 2:  # one straight segment: TOPP-RA's optimum is this trapezoid
        return trapezoid_trajectory(waypoints, joint_names, limits, dt, max_points), TimingReport("toppra")
    try:
        build = toppra_sections if method == "toppra" else ruckig_sections
        sections, report = build(waypoints, limits, Check(curve_free, certify_step, deadline), max_deviation)
    except ParameterizationFailed as exc:
        report = TimingReport("trapezoid", fallbacks=[f"{method}: {exc}"])
        return trapezoid_trajectory(waypoints, joint_names, limits, dt, max_points), report
    if report.corner_blends is not None:
        report.corner_blends = _at_rows(np.asarray(path, float), waypoints, report.corner_blends)
    report.min_clearance = certified_clearance(curve_free)
    return sample(sections, joint_names, waypoints[-1], dt, max_points, sample_deadline), report


def _at_rows(path: np.ndarray, waypoints: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (one per row of ``waypoints``: rows of ``path`` in order, as :func:`distinct` keeps them) at the
    rows of ``path`` they are (0 at the others)."""
    out, i = np.zeros(len(path)), 0
    for waypoint, value in zip(waypoints, values, strict=True):
        while not np.array_equal(path[i], waypoint):
            i += 1
        out[i] = value
        i += 1
    return out
