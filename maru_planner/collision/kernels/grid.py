"""A uniform grid of the obstacles' bounding boxes: the obstacles near a point in a large scene (numba).

Each obstacle is listed in every cell its box overlaps; one overlapping too many cells (a floor) goes in a ``big``
list that every query tests. :mod:`.sphere_scan` looks a cluster of spheres' obstacles up in it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

NO_GRID = np.zeros(6, dtype=np.int64), np.zeros(4)  # (ints, floats) of no grid: every obstacle is tested


@njit(cache=True, inline="always")
def cell_range(lo, hi, origin, h, n):
    """First and last cell (clamped to 0..n-1) along one axis of the interval [lo, hi]; first > last if outside."""
    a = int(np.floor((lo - origin) / h))
    b = int(np.floor((hi - origin) / h))
    return max(a, 0), min(b, n - 1)


@njit(cache=True, inline="always")
def _box_cells(box_lo, box_hi, k, origin, h, dims):
    i0, i1 = cell_range(box_lo[k, 0], box_hi[k, 0], origin[0], h, dims[0])
    j0, j1 = cell_range(box_lo[k, 1], box_hi[k, 1], origin[1], h, dims[1])
    l0, l1 = cell_range(box_lo[k, 2], box_hi[k, 2], origin[2], h, dims[2])
    return i0, i1, j0, j1, l0, l1, (i1 - i0 + 1) * (j1 - j0 + 1) * (l1 - l0 + 1)


@njit(cache=True)
def build_grid(box_lo, box_hi, h, max_cells):
    """A uniform grid of cell size ``h`` over obstacle boxes (n, 3): (ints, floats) for
    :func:`~maru_planner.collision.kernels.sphere_scan.classify_state`.

    Each obstacle is listed in every cell its box overlaps; one overlapping more than ``max_cells`` cells
    (a floor) goes in the ``big`` list that every query tests. ints: nx, ny, nz, n_cells, n_items, n_big,
    cell starts, items, big; floats: h and the grid's origin. Linear in the listed cells.
    """
    n = box_lo.shape[0]
    origin = np.empty(3)
    dims = np.empty(3, dtype=np.int64)
    for a in range(3):
        origin[a] = box_lo[:, a].min()
        dims[a] = max(1, int(np.ceil((box_hi[:, a].max() - origin[a]) / h)))
    ny, nz = dims[1], dims[2]
    n_cells = dims[0] * ny * nz
    counts = np.zeros(n_cells + 1, dtype=np.int64)
    big = np.zeros(n, dtype=np.bool_)
    for k in range(n):
        i0, i1, j0, j1, l0, l1, size = _box_cells(box_lo, box_hi, k, origin, h, dims)
        if size > max_cells:
            big[k] = True
            continue
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                for l in range(l0, l1 + 1):
                    counts[(i * ny + j) * nz + l + 1] += 1
    starts = np.cumsum(counts)
    items = np.empty(starts[-1], dtype=np.int64)
    fill = starts[:-1].copy()
    for k in range(n):
        if big[k]:
            continue
        i0, i1, j0, j1, l0, l1, _ = _box_cells(box_lo, box_hi, k, origin, h, dims)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                for l in range(l0, l1 + 1):
                    cell = (i * ny + j) * nz + l
                    items[fill[cell]] = k
                    fill[cell] += 1
    big_list = np.flatnonzero(big).astype(np.int64)
    head = np.array([dims[0], ny, nz, n_cells, items.shape[0], big_list.shape[0]], dtype=np.int64)
    ints = np.concatenate((head, starts, items, big_list))
    floats = np.array([h, origin[0], origin[1], origin[2]])
    return ints, floats


@njit(cache=True)
def unpack_grid(grid_i):
    """(cell starts, items, big) of :func:`build_grid`'s ints (empty arrays for :data:`NO_GRID`)."""
    n_cells, n_items, n_big = grid_i[3], grid_i[4], grid_i[5]
    o = 6
    n_starts = n_cells + 1 if n_cells > 0 else 0
    starts = grid_i[o : o + n_starts]
    o += n_starts
    items = grid_i[o : o + n_items]
    o += n_items
    return starts, items, grid_i[o : o + n_big]
