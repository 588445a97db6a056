"""How far a path stays from obstacles: exact distances to the nearest occupied cell centre.

Obstacles are the centres of occupied cells, as in the grid's inflation and the cost layer. At a cell
centre scipy's exact Euclidean distance transform is the answer; a point between centres (a smoothed
path) gets its exact distance from the transform's bounds at the four nearest centres (the distance
field is 1-Lipschitz) and a scan of the occupied cells in the annulus those bounds leave. Along a
segment the minimum is exact too: the point-to-segment distance over the occupied cells near it.

:func:`path_clearance` gives ``min_m`` (the exact minimum over the polyline) and ``mean_m`` (the mean
over arc length, sampled every quarter cell): what ``maru-base-plan --json`` and the benchmarks report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from scipy import ndimage

from maru_planner.base.grid import OccupancyGrid

SAMPLES_PER_CELL = 4


@dataclass(frozen=True)
class Clearance:
    """Distances (m) from a path to the nearest obstacle: the minimum and the mean along its length."""

    min_m: float
    mean_m: float

    def to_dict(self) -> dict[str, float | None]:
        """JSON-ready (an obstacle-free map gives None: no finite distance)."""
        return {k: (v if math.isfinite(v) else None) for k, v in (("min_m", self.min_m), ("mean_m", self.mean_m))}


def distance_transform(occupied: np.ndarray) -> np.ndarray:
    """Exact distance (in cells) from every cell centre to the nearest occupied one; inf without obstacles."""
    occupied = np.asarray(occupied, dtype=bool)
    if not occupied.any():
        return np.full(occupied.shape, np.inf)
    return ndimage.distance_transform_edt(~occupied)


@numba.njit(cache=True, nogil=True)
def _scan_row(occupied, row, pr, pc, lo, hi, best):
    """Smallest distance from (pr, pc) to an occupied centre of ``row`` with |x - pc| in [lo, hi] (cells)."""
    width = occupied.shape[1]
    dy = row + 0.5 - pr
    for side in (-1.0, 1.0):
        first = int(math.floor(pc + side * lo - 0.5)) if side > 0 else int(math.ceil(pc - hi - 0.5))
        last = int(math.ceil(pc + hi - 0.5)) if side > 0 else int(math.floor(pc - lo - 0.5))
        for col in range(max(first, 0), min(last, width - 1) + 1):
            if occupied[row, col]:
                d = math.hypot(col + 0.5 - pc, dy)
                if d < best:
                    best = d
    return best


@numba.njit(cache=True, nogil=True)
def point_distances(occupied, edt, points):
    """Exact distance (cells) from each (row, col) point, in cell units (centre of cell (r, c) = (r + .5, c + .5)),
    to the nearest occupied cell centre; ``edt`` is :func:`distance_transform` of ``occupied``."""
    height, width = occupied.shape
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        pr, pc = points[i, 0], points[i, 1]
        upper, lower = np.inf, 0.0
        r0, c0 = int(math.floor(pr - 0.5)), int(math.floor(pc - 0.5))
        for r in range(r0, r0 + 2):
            for c in range(c0, c0 + 2):
                rr, cc = min(max(r, 0), height - 1), min(max(c, 0), width - 1)
                gap = math.hypot(rr + 0.5 - pr, cc + 0.5 - pc)
                upper = min(upper, edt[rr, cc] + gap)
                lower = max(lower, edt[rr, cc] - gap)
        if not math.isfinite(upper):
            out[i] = np.inf
            continue
        upper += 1e-9
        lower = max(lower - 1e-9, 0.0)
        best = upper
        first, last = int(math.ceil(pr - upper - 0.5)), int(math.floor(pr + upper - 0.5))
        for row in range(max(first, 0), min(last, height - 1) + 1):
            dy = abs(row + 0.5 - pr)
            hi = math.sqrt(max(upper * upper - dy * dy, 0.0))
            lo = math.sqrt(lower * lower - dy * dy) if lower > dy else 0.0
            best = _scan_row(occupied, row, pr, pc, lo, hi, best)
        out[i] = best
    return out


@numba.njit(cache=True, nogil=True)
def segment_distance(occupied, a, b, upper):
    """Exact distance (cells) from segment a-b (cell units) to the nearest occupied centre, or ``upper`` when
    none lies within ``upper`` of the segment."""
    height, width = occupied.shape
    abr, abc = b[0] - a[0], b[1] - a[1]
    length2 = abr * abr + abc * abc
    best = upper
    r_first = int(math.ceil(min(a[0], b[0]) - upper - 0.5))
    r_last = int(math.floor(max(a[0], b[0]) + upper - 0.5))
    c_first = int(math.ceil(min(a[1], b[1]) - upper - 0.5))
    c_last = int(math.floor(max(a[1], b[1]) + upper - 0.5))
    for row in range(max(r_first, 0), min(r_last, height - 1) + 1):
        for col in range(max(c_first, 0), min(c_last, width - 1) + 1):
            if not occupied[row, col]:
                continue
            qr, qc = row + 0.5 - a[0], col + 0.5 - a[1]
            t = 0.0 if length2 == 0.0 else min(max((qr * abr + qc * abc) / length2, 0.0), 1.0)
            d = math.hypot(qr - t * abr, qc - t * abc)
            if d < best:
                best = d
    return best


def to_cell_units(grid: OccupancyGrid, xy: np.ndarray) -> np.ndarray:
    """Map-frame (x, y) rows -> continuous (row, col) in cell units (cell (r, c) spans [r, r + 1) x [c, c + 1))."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    ox, oy, yaw = grid.origin
    dx, dy = xy[:, 0] - ox, xy[:, 1] - oy
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([(-s * dx + c * dy), (c * dx + s * dy)]) / grid.resolution


def from_cell_units(grid: OccupancyGrid, rc: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_cell_units`."""
    rc = np.asarray(rc, dtype=float).reshape(-1, 2) * grid.resolution
    ox, oy, yaw = grid.origin
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([ox + c * rc[:, 1] - s * rc[:, 0], oy + s * rc[:, 1] + c * rc[:, 0]])


def resample(points: np.ndarray, per_cell: int = SAMPLES_PER_CELL) -> tuple[np.ndarray, np.ndarray]:
    """Points every <= 1/per_cell along a polyline (cell units, vertices kept) and the segment each lies on."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(points) < 2:
        return points.copy(), np.zeros(len(points), dtype=np.int64)
    out, owner = [], []
    for j, (a, b) in enumerate(zip(points[:-1], points[1:], strict=True)):
        steps = max(int(math.ceil(per_cell * math.hypot(*(b - a)))), 1)
        t = np.arange(steps)[:, None] / steps
        out.append(a + t * (b - a))
        owner.append(np.full(steps, j))
    out.append(points[-1:])
    owner.append(np.array([len(points) - 2]))
    return np.concatenate(out), np.concatenate(owner)


def path_clearance(grid: OccupancyGrid, path: np.ndarray, edt: np.ndarray | None = None) -> Clearance:
    """Exact minimum and arc-length mean distance (m) from the path's (x, y) polyline to the grid's obstacles.

    ``edt``: :func:`distance_transform` of ``grid.occupied`` when the caller has it (several paths, one map).
    """
    path = np.asarray(path, dtype=float)
    xy = path.reshape(-1, path.shape[-1])[:, :2] if path.size else np.zeros((0, 2))
    if len(xy) == 0:
        return Clearance(math.nan, math.nan)
    occupied = np.ascontiguousarray(grid.occupied, dtype=np.bool_)
    edt = distance_transform(occupied) if edt is None else edt
    points = to_cell_units(grid, xy)
    samples, owner = resample(points)
    values = point_distances(occupied, edt, samples)
    if not np.isfinite(values).all():
        return Clearance(math.inf, math.inf)
    lowest = float(values.min())
    sampled = np.full(max(len(points) - 1, 1), np.inf)
    np.minimum.at(sampled, owner, values)  # an upper bound of each segment's minimum: scan only within it
    for j in range(len(points) - 1):
        lowest = min(lowest, segment_distance(occupied, points[j], points[j + 1], float(sampled[j]) + 1e-9))
    steps = np.linalg.norm(np.diff(samples, axis=0), axis=1)
    if steps.sum() > 0:
        mean = float(np.sum(steps * (values[:-1] + values[1:]) / 2.0) / steps.sum())
    else:
        mean = float(values.mean())
    return Clearance(lowest * grid.resolution, mean * grid.resolution)
