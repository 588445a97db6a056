"""Path smoothing in the spirit of Nav2's simple smoother, with the guards a grid path needs.

Each free vertex moves as in Nav2's ``SimpleSmoother`` (Gauss-Seidel sweeps of
``y_i += w_data (x_i - y_i) + w_smooth (y_{i-1} + y_{i+1} - 2 y_i)`` until the sweep's total motion is
below ``tolerance`` or ``max_its`` sweeps ran), but a move is taken only when, for both segments it
changes:

- every cell the segment touches is free on the planner's own map (``blocked``: the grown map of a disc
  planner, the footprint's C-space layer at the stretch's heading for an SE(2) path; each sample every
  quarter cell also tests the cells within a quarter cell of it, so grazing a corner counts as touching);
- its exact distance to the nearest obstacle (:mod:`clearance`, up to ``cap``) is at least the smallest
  distance of the original path's segments around it (the same segment and its two neighbours): the
  smoothed path never comes closer to an obstacle than the planned one did there;
- with ``min_turning_radius`` > 0, no vertex turns sharper (angle per unit length) than 1 / radius or
  than the original path already did at that vertex.

A path is smoothed in *stretches* (first and last vertex fixed): a disc path is one stretch, an SE(2)
path one per run of poses at one heading (its turns in place stay where the planner put them). The
result is checked again, every segment that changed; if anything fails, the original path is returned.
All of it runs in cell units (cell (r, c) spans [r, r + 1) x [c, c + 1)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from maru_planner.base.budget import Deadline, unlimited
from maru_planner.base.clearance import segment_distance
from maru_planner.base.kernels import now
from maru_planner.params import param

_EPS = 1e-9


@dataclass(frozen=True)
class SmootherParams:
    """Nav2 simple smoother's parameters (its defaults) and the turning-radius limit of the constrained one."""

    w_data: float = param(0.2, "weight pulling each vertex back to the planned path", lower=0.0, upper=1.0)
    w_smooth: float = param(0.3, "weight pulling each vertex towards its neighbours' midpoint", lower=0.0, upper=0.5)
    tolerance: float = param(1e-10, "stop when a sweep moves the vertices less than this in total (cells)", lower=0.0)
    max_its: int = param(1000, "most Gauss-Seidel sweeps", lower=1, upper=100000)
    min_turning_radius: float = param(0.0, "m; 0 = turning in place allowed (the SE(2) lattice's)", lower=0.0)


@dataclass
class Stretch:
    """Vertices ``first..last`` of a path (inclusive), smoothed against ``blocked`` (cells, offset by ``offset``)."""

    first: int
    last: int
    blocked: np.ndarray
    offset: tuple[int, int] = (0, 0)


@dataclass
class SmoothOutcome:
    """The smoothed vertices (cell units) and what happened."""

    points: np.ndarray
    sweeps: int
    moved: int  # vertices that moved
    accepted: bool  # False: the re-check failed or the deadline passed, ``points`` are the original


@numba.njit(cache=True, nogil=True)
def _cell_blocked(blocked, off_r, off_c, r, c):
    rr, cc = r - off_r, c - off_c
    if rr < 0 or cc < 0 or rr >= blocked.shape[0] or cc >= blocked.shape[1]:
        return True
    return blocked[rr, cc]


@numba.njit(cache=True, nogil=True)
def segment_free(blocked, off_r, off_c, a, b):
    """No cell within a quarter cell of a sample (every quarter cell) of segment a-b is blocked."""
    steps = max(int(math.ceil(4.0 * math.hypot(b[0] - a[0], b[1] - a[1]))), 1)
    for s in range(steps + 1):
        t = s / steps
        pr = a[0] + t * (b[0] - a[0])
        pc = a[1] + t * (b[1] - a[1])
        for dr in (-0.25, 0.25):
            for dc in (-0.25, 0.25):
                if _cell_blocked(blocked, off_r, off_c, int(math.floor(pr + dr)), int(math.floor(pc + dc))):
                    return False
    return True


@numba.njit(cache=True, nogil=True)
def capped_clearance(occupied, dist, a, b, cap):
    """Exact distance (cells) from segment a-b to the obstacles, capped at ``cap``.

    ``dist``: exact centre distances (cells) where at most ``cap`` + 3 cells, inf beyond: far from every
    obstacle the scan is skipped.
    """
    height, width = dist.shape
    r = min(max(int(math.floor(a[0])), 0), height - 1)
    c = min(max(int(math.floor(a[1])), 0), width - 1)
    near = dist[r, c] if math.isfinite(dist[r, c]) else cap + 3.0
    gap = math.hypot(r + 0.5 - a[0], c + 0.5 - a[1]) + math.hypot(b[0] - a[0], b[1] - a[1])
    if near - gap >= cap:
        return cap
    return segment_distance(occupied, a, b, cap)


@numba.njit(cache=True, nogil=True)
def _turn_rate(p, q, s):
    """Heading change at q per unit length (mean of the two segments), 0 at a degenerate vertex."""
    ar, ac, br, bc = q[0] - p[0], q[1] - p[1], s[0] - q[0], s[1] - q[1]
    la, lb = math.hypot(ar, ac), math.hypot(br, bc)
    if la < 1e-12 or lb < 1e-12:
        return 0.0
    angle = abs(math.atan2(ar * bc - ac * br, ar * br + ac * bc))
    return angle / (0.5 * (la + lb))


@numba.njit(cache=True, nogil=True)
def _turns_ok(y, i, n, max_turn, turn0):
    for j in range(max(i - 1, 1), min(i + 1, n - 2) + 1):
        if _turn_rate(y[j - 1], y[j], y[j + 1]) > max(max_turn, turn0[j]) + 1e-9:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _smooth_kernel(
    x,
    fixed,
    blocked,
    off_r,
    off_c,
    occupied,
    dist,
    cap,
    baseline,
    w_data,
    w_smooth,
    max_its,
    tolerance,
    max_turn,
    turn0,
    deadline_at,
):
    """Gauss-Seidel sweeps with the guards (module doc); returns (points, sweeps, timed out)."""
    n = x.shape[0]
    y = x.copy()
    cand = np.empty(2)
    for sweep in range(max_its):
        if now() > deadline_at[0]:
            return y, sweep, True
        change = 0.0
        for i in range(1, n - 1):
            if fixed[i]:
                continue
            for k in range(2):
                cand[k] = y[i, k] + w_data * (x[i, k] - y[i, k]) + w_smooth * (y[i - 1, k] + y[i + 1, k] - 2 * y[i, k])
            step = math.hypot(cand[0] - y[i, 0], cand[1] - y[i, 1])
            if step < 1e-12:
                continue
            if not (
                segment_free(blocked, off_r, off_c, y[i - 1], cand)
                and segment_free(blocked, off_r, off_c, cand, y[i + 1])
            ):
                continue
            if capped_clearance(occupied, dist, y[i - 1], cand, cap) < baseline[i - 1] - _EPS:
                continue
            if capped_clearance(occupied, dist, cand, y[i + 1], cap) < baseline[i] - _EPS:
                continue
            old0, old1 = y[i, 0], y[i, 1]
            y[i, 0], y[i, 1] = cand[0], cand[1]
            if max_turn > 0.0 and not _turns_ok(y, i, n, max_turn, turn0):
                y[i, 0], y[i, 1] = old0, old1
                continue
            change += step
        if change < tolerance:
            return y, sweep + 1, False
    return y, max_its, False


@numba.njit(cache=True, nogil=True)
def segment_clearances(occupied, dist_cells, points, cap):
    """Capped exact clearance (cells) of each segment of a polyline (cell units)."""
    out = np.empty(max(points.shape[0] - 1, 0))
    for j in range(points.shape[0] - 1):
        out[j] = capped_clearance(occupied, dist_cells, points[j], points[j + 1], cap)
    return out


def turn_rates(points: np.ndarray) -> np.ndarray:
    """Heading change per unit length at each vertex (0 at the ends)."""
    out = np.zeros(len(points))
    for j in range(1, len(points) - 1):
        out[j] = _turn_rate(points[j - 1], points[j], points[j + 1])
    return out


def smooth_stretch(
    points: np.ndarray,
    stretch: Stretch,
    occupied: np.ndarray,
    dist_cells: np.ndarray,
    cap: float,
    params: SmootherParams,
    resolution: float,
    deadline: Deadline | None = None,
) -> SmoothOutcome:
    """Smooth vertices ``stretch.first..last`` of ``points`` (cell units); the others and both ends stay."""
    deadline = deadline or unlimited()
    x = np.ascontiguousarray(points[stretch.first : stretch.last + 1], dtype=np.float64)
    if len(x) < 3:
        return SmoothOutcome(x, 0, 0, True)
    occupied = np.ascontiguousarray(occupied, dtype=np.bool_)
    blocked = np.ascontiguousarray(stretch.blocked, dtype=np.bool_)
    own = segment_clearances(occupied, dist_cells, x, float(cap))
    baseline = own.copy()  # the smallest clearance of the original segment and its two neighbours
    baseline[1:] = np.minimum(baseline[1:], own[:-1])
    baseline[:-1] = np.minimum(baseline[:-1], own[1:])
    fixed = np.zeros(len(x), dtype=np.bool_)
    fixed[0] = fixed[-1] = True
    max_turn = resolution / params.min_turning_radius if params.min_turning_radius > 0 else 0.0
    turn0 = turn_rates(x) if max_turn > 0 else np.zeros(len(x))
    y, sweeps, timed_out = _smooth_kernel(
        x,
        fixed,
        blocked,
        stretch.offset[0],
        stretch.offset[1],
        occupied,
        dist_cells,
        float(cap),
        baseline,
        float(params.w_data),
        float(params.w_smooth),
        int(params.max_its),
        float(params.tolerance),
        max_turn,
        turn0,
        deadline.kernel_at,
    )
    if timed_out or not _recheck(x, y, blocked, stretch.offset, occupied, dist_cells, cap, baseline, max_turn, turn0):
        return SmoothOutcome(x, sweeps, 0, False)
    moved = int(np.count_nonzero(np.hypot(*(y - x).T) > 1e-9))
    return SmoothOutcome(y, sweeps, moved, True)


def _recheck(x, y, blocked, offset, occupied, dist_cells, cap, baseline, max_turn, turn0) -> bool:
    """The smoothed stretch again: every changed segment free and as far from obstacles as required, turns kept."""
    if not _segments_hold(x, y, blocked, offset[0], offset[1], occupied, dist_cells, float(cap), baseline):
        return False
    if max_turn > 0:
        return bool(np.all(turn_rates(y) <= np.maximum(max_turn, turn0) + 1e-9))
    return True


@numba.njit(cache=True, nogil=True)
def _segments_hold(x, y, blocked, off_r, off_c, occupied, dist, cap, baseline):
    for j in range(y.shape[0] - 1):
        moved = (x[j, 0] != y[j, 0] or x[j, 1] != y[j, 1]) or (x[j + 1, 0] != y[j + 1, 0] or x[j + 1, 1] != y[j + 1, 1])
        if not moved:
            continue  # the planner's own segment
        if not segment_free(blocked, off_r, off_c, y[j], y[j + 1]):
            return False
        if capped_clearance(occupied, dist, y[j], y[j + 1], cap) < baseline[j] - _EPS:
            return False
    return True


def stretches_at_headings(path: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges [first, last] of an SE(2) path's runs at one heading (turns in place split them)."""
    runs, first = [], 0
    for i in range(1, len(path)):
        turned = not math.isclose(path[i, 2], path[i - 1, 2], abs_tol=1e-9)
        if turned:
            if i - 1 > first:
                runs.append((first, i - 1))
            first = i
    if len(path) - 1 > first:
        runs.append((first, len(path) - 1))
    return runs
