"""The blended curve through a path: parabolic blends at its corners, straight lines between them.

Each corner is replaced by a parabolic blend: a quadratic Bézier from ``P − l·u_in`` through control point ``P`` to
``P + l·u_out``, whose distance from the corner, ``l·|u_out − u_in| / 4``, is at most the requested deviation (and
``l`` at most half of either adjacent segment). The straight parts of the blended curve lie on the path; where a
corner has no blend the motion stops there and the path is cut into :func:`sections`.
"""

from __future__ import annotations

import math

import numpy as np
import toppra.interpolator

from maru_planner.trajectory.curves import Curve

# A blend is certified as this many bent segments: each gets its own joint-speed bound (dq/dt runs from the incoming
# to the outgoing direction). 4 took Maru-1's blend certification from 10.7 to 7.5 ms a plan (1 part) and 9.4 (8).
BLEND_BEND_PARTS = 4
SHARED_END = 1e-12  # rad: a straight part this short between two blends is their shared end (nothing to prove)
MIN_BLEND_SPEED = 0.1  # |u_in + u_out| below this (a near reversal): stop instead of blending
GRID_INTERVALS = 30  # toppra grid intervals along a section (plus ≥ BLEND_INTERVALS per blend)
BLEND_INTERVALS = 3
# rad: farthest a waypoint drop_collinear leaves out may be from the line that replaces it (bodies then move at most
# ~their levers x this: far within the 1e-6 m tolerance every certified bound gives away)
COLLINEAR_OFFSET = 1e-9


class BlendedPath(toppra.interpolator.AbstractGeometricPath):
    """A polyline whose corners are parabolic blends; C¹ in the path parameter ``s`` (see module doc).

    Every piece is ``p(σ) = p0 + v0·σ + ½·dd·σ²`` for ``σ = s − s_start`` (lines: |v0| = 1, dd = 0).
    ``half_lengths[k]`` is the blend size ``l`` at waypoint k (> 0 for every interior waypoint).
    """

    def __init__(self, waypoints: np.ndarray, half_lengths: np.ndarray):
        units = unit_directions(waypoints)
        inner = len(waypoints) - 2  # blends: one per interior waypoint; pieces in order line 0, blend 1, line 1, ...
        straight = np.linalg.norm(np.diff(waypoints, axis=0), axis=1) - half_lengths[:-1] - half_lengths[1:]
        blend = half_lengths[1:-1]
        line_p0 = waypoints[:-1] + half_lengths[:-1, None] * units
        blend_p0 = waypoints[1:-1] - blend[:, None] * units[:-1]
        blend_dd = (units[1:] - units[:-1]) / (2.0 * blend[:, None])
        order = np.empty(2 * inner + 1, dtype=int)  # position of each piece among [lines..., blends...]
        order[0::2], order[1::2] = np.arange(inner + 1), inner + 1 + np.arange(inner)
        keep = np.concatenate([straight > SHARED_END, np.ones(inner, dtype=bool)])[order]
        order = order[keep]
        lengths = np.concatenate([straight, 2.0 * blend])[order]
        self.starts = np.concatenate([[0.0], np.cumsum(lengths)])
        self.p0 = np.concatenate([line_p0, blend_p0])[order]
        self.v0 = np.concatenate([units, units[:-1]])[order]
        self.dd = np.concatenate([np.zeros_like(units), blend_dd])[order]
        self.blend_of = np.concatenate([np.full(inner + 1, -1), np.arange(1, inner + 1)])[order]  # -1: a line
        self.end = waypoints[-1]

    @property
    def dof(self) -> int:
        return self.p0.shape[1]

    @property
    def path_interval(self) -> np.ndarray:
        return np.array([0.0, self.starts[-1]])

    @property
    def waypoints(self):
        return self.starts, self.p0

    def __call__(self, path_positions, order: int = 0) -> np.ndarray:
        ss = np.atleast_1d(np.asarray(path_positions, float))
        piece = np.clip(np.searchsorted(self.starts, ss, side="right") - 1, 0, len(self.p0) - 1)
        out = self.at(ss, piece, order)
        return out if np.ndim(path_positions) else out[0]

    def at(self, ss: np.ndarray, piece: np.ndarray, order: int) -> np.ndarray:
        """Derivative ``order`` (0–2) at path positions ``ss`` on the given pieces."""
        sigma = (ss - self.starts[piece])[:, None]
        if order == 0:
            return self.p0[piece] + self.v0[piece] * sigma + 0.5 * self.dd[piece] * sigma**2
        if order == 1:
            return self.v0[piece] + self.dd[piece] * sigma
        if order == 2:
            return self.dd[piece].copy()
        raise ValueError(f"order must be 0, 1 or 2, got {order}")

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """toppra grid points (every piece boundary included) and the piece of each grid interval."""
        s0, lengths = self.starts[:-1], np.diff(self.starts)
        least = np.where(self.blend_of >= 0, BLEND_INTERVALS, 1)
        n = np.maximum(least, np.ceil(GRID_INTERVALS * lengths / self.starts[-1]).astype(int))
        pieces = np.repeat(np.arange(len(n)), n)
        step = np.arange(len(pieces)) - np.repeat(np.cumsum(n) - n, n)  # interval index within its piece
        points = s0[pieces] + lengths[pieces] * (step / n[pieces])
        return np.append(points, self.starts[-1]), pieces


def unit_directions(waypoints: np.ndarray) -> np.ndarray:
    """The unit direction of each segment of ``waypoints`` (rows: segments)."""
    delta = np.diff(waypoints, axis=0)
    return delta / np.linalg.norm(delta, axis=1)[:, None]


def parabola_parts(start: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray, length: np.ndarray,
                   parts: int = BLEND_BEND_PARTS) -> list[Curve]:  # fmt: skip
    """Per row k, ``p(σ) = start[k] + velocity[k]·σ + ½·acceleration[k]·σ²`` on ``[0, length[k]]`` as ``parts`` bent
    segments (:data:`Curve`): ends, no chord deviation, and each part's bend ``½·h²·p''`` (h its length in σ): on it
    ``p = (1 - t)·p(start) + t·p(end) + (t² - t)·bend``. All rows in one set of array operations."""
    sigma = np.linspace(0.0, length, parts + 1, axis=1)[..., None]  # (rows, parts + 1, 1)
    ends = start[:, None] + velocity[:, None] * sigma + 0.5 * acceleration[:, None] * sigma**2
    bends = np.repeat((0.5 * ((length / parts) ** 2)[:, None] * acceleration)[:, None], parts, axis=1)
    on_chord = np.zeros(start.shape[1])
    return [(ends[k], on_chord, bends[k]) for k in range(len(length))]


def parabola_chords(start: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray, length: float,
                    step: float) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Points along the parabola of :func:`parabola_parts` at most ``step`` apart in σ (|p'| ≤ 1 on a blend, so a
    path step bounds the joint step) and, per joint, how far it leaves the chords between them (|p''|·h²/8)."""
    sigma = np.linspace(0.0, length, max(2, math.ceil(length / step) + 1))
    h = sigma[1] - sigma[0]
    points = start + velocity * sigma[:, None] + 0.5 * acceleration * sigma[:, None] ** 2
    return points, np.abs(acceleration) * h * h / 8.0


def blend_half_lengths(waypoints: np.ndarray, deviation: np.ndarray, units: np.ndarray | None = None) -> np.ndarray:
    """Blend size ``l`` at every waypoint for corner deviations ≤ ``deviation`` (one per waypoint; 0: stop there), 0
    at the ends and at near reversals; ``units``: the path's :func:`unit_directions` if at hand."""
    half = np.zeros(len(waypoints))
    if len(waypoints) < 3:
        return half
    units = unit_directions(waypoints) if units is None else units
    u_in, u_out = units[:-1], units[1:]
    turn = np.linalg.norm(u_out - u_in, axis=1)
    segment = np.linalg.norm(np.diff(waypoints, axis=0), axis=1)
    # A blend may take all of a first or last segment, half of a segment it shares with another blend.
    before, after = 0.5 * segment[:-1], 0.5 * segment[1:]
    before[0], after[-1] = segment[0], segment[-1]
    dev = np.asarray(deviation, dtype=float)[1:-1]
    blended = (dev > 0.0) & (np.linalg.norm(u_in + u_out, axis=1) >= MIN_BLEND_SPEED)
    with np.errstate(divide="ignore"):
        half[1:-1] = np.where(blended, np.minimum(4.0 * dev / turn, np.minimum(before, after)), 0.0)
    return half


def deviation_from_path(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Euclidean distance of each of ``points`` from the polyline ``path`` (rad)."""
    points, path = np.atleast_2d(points), np.atleast_2d(path)
    if len(path) == 1:
        return np.linalg.norm(points - path[0], axis=1)
    a, seg = path[:-1], np.diff(path, axis=0)
    length2 = np.maximum((seg * seg).sum(axis=1), 1e-300)
    rel = points[:, None, :] - a[None]
    t = np.clip((rel * seg[None]).sum(axis=2) / length2, 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * seg[None], axis=2).min(axis=1)


def sections(waypoints: np.ndarray, half: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(waypoints, half lengths) of each stretch between stops."""
    cuts = [0] + [k for k in range(1, len(waypoints) - 1) if half[k] == 0.0] + [len(waypoints) - 1]
    out = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        h = half[a : b + 1].copy()
        h[0] = h[-1] = 0.0
        out.append((waypoints[a : b + 1], h))
    return out


def distinct(path: np.ndarray) -> np.ndarray:
    """``path`` without repeated or collinear interior waypoints: none farther than :data:`COLLINEAR_OFFSET` from
    the line the curve then follows, so what certification proves of ``path`` holds for the curve."""
    if len(path) < 2:
        return path
    keep = np.concatenate([[True], np.linalg.norm(np.diff(path, axis=0), axis=1) > 1e-12])
    path = path[keep]
    return drop_collinear(path) if len(path) > 2 else path


def drop_collinear(path: np.ndarray, tol: float = 1e-9, max_offset: float = COLLINEAR_OFFSET) -> np.ndarray:
    """Remove interior waypoints lying on the straight line between their neighbours (no checks needed): each one
    within ``max_offset`` (rad) of the segment between the waypoints kept around it.

    A waypoint goes when its steps in and out point the same way (``tol``, on their dot product) or its step in is
    shorter than ``tol``; then, Douglas-Peucker, between two kept waypoints the farthest one more than
    ``max_offset`` off their segment is kept too, until none is (so small turns do not add up to a dropped bend).
    """
    if len(path) < 3:
        return path
    step = np.diff(path, axis=0)
    norms = np.linalg.norm(step, axis=1)
    na, nb = norms[:-1], norms[1:]
    dots = np.einsum("ij,ij->i", step[:-1], step[1:])
    on_line = (na < tol) | ((nb > tol) & (np.abs(dots - na * nb) <= tol * np.maximum(1.0, na * nb)))
    keep = np.flatnonzero(np.concatenate([[True], ~on_line, [True]]))
    while len(keep) < len(path):
        off = _offsets(path, keep)
        worst = np.maximum.reduceat(off, keep[:-1])  # per kept segment (its start's offset is 0)
        far = worst > max_offset
        if not far.any():
            break
        extra = [a + int(np.argmax(off[a:b])) for a, b in zip(keep[:-1][far], keep[1:][far], strict=True)]
        keep = np.sort(np.concatenate([keep, extra]))
    return path[keep]


def _offsets(path: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Per row of ``path``, its distance from the segment between the ``keep`` rows around it (0 for kept rows)."""
    rows = np.arange(len(path))
    before = keep[np.maximum(np.searchsorted(keep, rows, side="right") - 1, 0)]
    after = keep[np.minimum(np.searchsorted(keep, rows), len(keep) - 1)]
    span, rel = path[after] - path[before], path - path[before]
    t = np.clip(np.einsum("ij,ij->i", rel, span) / np.maximum(np.einsum("ij,ij->i", span, span), 1e-300), 0.0, 1.0)
    return np.linalg.norm(rel - t[:, None] * span, axis=1)
