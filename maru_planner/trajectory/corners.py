"""Blended corners, certified: the blend size at every corner of a path, each blend re-checked for collision.

Every blend is re-checked by the caller's curve check (:mod:`~maru_planner.trajectory.curves`). A blend that collides
is retried with a quarter of its deviation, twice; then the motion stops at that corner (the path is split there).
Past the check's deadline no blend is certified any more, so the corners left stop.
"""

from __future__ import annotations

import time

import numpy as np

from maru_planner.trajectory.blends import (
    SHARED_END,
    blend_half_lengths,
    parabola_chords,
    parabola_parts,
    unit_directions,
)
from maru_planner.trajectory.curves import Check, Curve, takes_bends
from maru_planner.trajectory.report import TimingReport

BLEND_SHRINK = 4.0  # each retry of a colliding blend divides its deviation by this
BLEND_RETRIES = 2  # retries before a corner becomes a stop


def certified_half_lengths(
    waypoints: np.ndarray, max_deviation: float, check: Check, report: TimingReport, with_pieces: bool = False
) -> np.ndarray:
    """Blend size per waypoint (0 at the ends and at stops), every blend re-checked (module doc). ``with_pieces``:
    the checks also prove the straight pieces between the blends (:func:`_pieces_to_prove`); ``report`` tells
    whether every straight part of the final curve lies on one proven (``curve_certified``)."""
    half = np.zeros(len(waypoints))
    t0 = time.monotonic()
    deviation = np.full(len(waypoints), float(max_deviation))
    pending = list(range(1, len(waypoints) - 1))
    units = unit_directions(waypoints)
    lengths = np.linalg.norm(np.diff(waypoints, axis=0), axis=1)
    proven_ends = np.full((len(waypoints) - 1, 2), np.inf)  # per segment: the blend sizes its proven piece left out
    for attempt in range(BLEND_RETRIES + 1):  # all pending corners in one check: they share the certification's work
        half[pending] = blend_half_lengths(waypoints, deviation, units)[pending]
        pending = [k for k in pending if half[k] > 0.0]
        if not pending:
            break
        curves = _corner_curves(waypoints, units, np.array(pending), half, check)
        report.certify_checks += sum(len(curve[0]) for curve in curves)
        segments, ends, pieces = (
            _pieces_to_prove(waypoints, units, lengths, half, pending, attempt) if with_pieces else ([], half, [])
        )
        free = check.many(curves + pieces)
        for i, proven in zip(segments, free[len(curves) :], strict=True):
            if proven:
                proven_ends[i] = ends[i], ends[i + 1]
        failed = [k for k, ok in zip(pending, free[: len(curves)], strict=True) if not ok]
        for k in failed:
            report.fallbacks.append(f"blend at waypoint {k} not certified at deviation {deviation[k]:.3g} rad")
            half[k] = 0.0
            deviation[k] /= BLEND_SHRINK
        pending = failed
    report.certify_time += time.monotonic() - t0
    count_corners(waypoints, half, report)
    if with_pieces:
        straight = lengths - half[:-1] - half[1:] > SHARED_END
        report.curve_certified = bool(np.all(~straight | ((proven_ends[:, 0] <= half[:-1])
                                                         & (proven_ends[:, 1] <= half[1:]))))  # fmt: skip
    return half


def _pieces_to_prove(waypoints: np.ndarray, units: np.ndarray, lengths: np.ndarray, half: np.ndarray,
                     pending: list[int], attempt: int) -> tuple[list[int], np.ndarray, list[Curve]]:  # fmt: skip
    """The segments whose straight pieces to prove with the blends of ``attempt``, the blend size left out at each
    waypoint, and the pieces as curves: first every segment without the ends its blends (``half``) take; at the
    first retry, the segments next to a retried corner, up to that corner (wherever its blend ends up, or if the
    motion stops there, the straight part left lies on them); none after."""
    if attempt == 0:
        segments, ends = np.arange(len(waypoints) - 1), half
    elif attempt == 1:
        segments = np.unique(np.concatenate([np.array(pending) - 1, pending]))
        ends = half.copy()
        ends[pending] = 0.0
    else:
        return [], half, []
    segments = segments[lengths[segments] - ends[segments] - ends[segments + 1] > SHARED_END]
    lines = np.stack([waypoints[segments] + ends[segments, None] * units[segments],
                      waypoints[segments + 1] - ends[segments + 1, None] * units[segments]], axis=1)  # fmt: skip
    return segments.tolist(), ends, [(line, np.zeros(waypoints.shape[1])) for line in lines]


def _corner_curves(waypoints: np.ndarray, units: np.ndarray, corners: np.ndarray, half: np.ndarray, check: Check
                   ) -> list[Curve]:  # fmt: skip
    """The blends of ``corners`` (the parabolas a :class:`BlendedPath` puts there, ``half`` their sizes by waypoint)
    as ``check`` takes them: :data:`BLEND_BEND_PARTS` bent segments, else chords ``check.step`` apart."""
    u_in, u_out, h = units[corners - 1], units[corners], half[corners][:, None]
    start, acceleration = waypoints[corners] - h * u_in, (u_out - u_in) / (2.0 * h)
    if takes_bends(check.curve_free):
        return parabola_parts(start, u_in, acceleration, 2.0 * h[:, 0])
    return [parabola_chords(s, v, a, 2.0 * length, check.step)
            for s, v, a, length in zip(start, u_in, acceleration, h[:, 0], strict=True)]  # fmt: skip


def count_corners(waypoints: np.ndarray, half: np.ndarray, report: TimingReport) -> None:
    """Blends, stops and the largest distance of a blend's middle from its corner (``l·|u_out − u_in| / 4``)."""
    interior = half[1:-1]
    report.blends = int(np.count_nonzero(interior > 0))
    report.stops = len(interior) - report.blends
    if report.blends:
        turn = np.linalg.norm(np.diff(unit_directions(waypoints), axis=0), axis=1)
        report.max_deviation = float(np.max(0.25 * interior * turn))
