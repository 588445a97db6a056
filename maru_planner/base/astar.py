"""2-D grid A*: 8-connected, octile costs, no corner cutting, optimal.

API (used by ``mspp.py`` and helper-8's ``tunnel.py``)::

    path, cost, expansions = astar_2d(occupied, start_cell, goal_cell)

- ``occupied``: bool array ``(height, width)`` (row = y, col = x), e.g.
  ``grid.occupied`` or ``grid.inflate(r).occupied``.
- ``start_cell``, ``goal_cell``: ``(row, col)``; outside the map -> ValueError.
- returns an :class:`AStarResult` (a NamedTuple, so it unpacks as above):
  ``path`` int array ``(n, 2)`` of (row, col) from start to goal (empty
  ``(0, 2)`` when there is no path or start/goal is occupied), ``cost`` in
  cells (straight 1, diagonal sqrt 2; ``inf`` without a path), ``expansions``.

A diagonal move needs both side cells free (the MovingAI convention), so the
octile heuristic is consistent and the first pop of the goal is optimal. Ties
on f are broken towards larger g. The kernel is compiled with numba
(``cache=True``); ``use_numba=False`` (or a missing numba) runs the pure-Python
version of the same algorithm.
"""

from __future__ import annotations

import heapq
import math
from typing import NamedTuple

import numpy as np

try:
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - numba is in requirements; keep the fallback honest
    numba = None
    HAVE_NUMBA = False

SQRT2 = math.sqrt(2.0)
# (drow, dcol, cost) of the 8 moves: straight first, then diagonal.
MOVES = np.array(
    [[0, 1], [1, 0], [0, -1], [-1, 0], [1, 1], [1, -1], [-1, 1], [-1, -1]],
    dtype=np.int64,
)


class AStarResult(NamedTuple):
    path: np.ndarray
    cost: float
    expansions: int


def octile(dr: float, dc: float) -> float:
    dr, dc = abs(dr), abs(dc)
    return max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc)


# --------------------------------------------------------------------- numba
def _njit(func):
    return numba.njit(cache=True, nogil=True)(func) if HAVE_NUMBA else func


@_njit
def _heap_push(keys, gs, ids, size, key, g, node):
    """Binary min-heap ordered by key, then larger g first: sift the hole up, then place."""
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        pk = keys[parent]
        if pk < key or (pk == key and gs[parent] >= g):
            break
        keys[i] = pk
        gs[i] = gs[parent]
        ids[i] = ids[parent]
        i = parent
    keys[i] = key
    gs[i] = g
    ids[i] = node
    return size + 1


@_njit
def _heap_pop(keys, gs, ids, size):
    node = ids[0]
    g = gs[0]
    size -= 1
    key = keys[size]
    lg = gs[size]
    lid = ids[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        right = child + 1
        if right < size and (keys[right] < keys[child] or (keys[right] == keys[child] and gs[right] > gs[child])):
            child = right
        ck = keys[child]
        if key < ck or (key == ck and lg >= gs[child]):
            break
        keys[i] = ck
        gs[i] = gs[child]
        ids[i] = ids[child]
        i = child
    keys[i] = key
    gs[i] = lg
    ids[i] = lid
    return node, g, size


@_njit
def _astar_kernel(blocked, sr, sc, gr, gc, cell_cost, use_cost):
    """A* on a grid padded with one blocked cell on every side.

    ``blocked`` is the padded (height + 2, width + 2) array; cells are given in
    padded coordinates. Returns (parent array over padded cells, goal cost or
    -1, expansions). With ``use_cost``, entering a cell adds ``cell_cost``
    (padded, >= 0) to the move cost: the heuristic stays admissible.
    """
    height, width = blocked.shape
    flat = blocked.ravel()
    n = height * width
    g_best = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    capacity = 8 * n + 1
    keys = np.empty(capacity)
    gs = np.empty(capacity)
    ids = np.empty(capacity, dtype=np.int64)
    sqrt2 = np.sqrt(2.0)
    diag_extra = sqrt2 - 1.0
    drs = np.array([0, 1, 0, -1, 1, 1, -1, -1])
    dcs = np.array([1, 0, -1, 0, 1, -1, 1, -1])
    offsets = drs * width + dcs
    start = sr * width + sc
    goal = gr * width + gc
    g_best[start] = 0.0
    dr0 = abs(sr - gr)
    dc0 = abs(sc - gc)
    h0 = max(dr0, dc0) + diag_extra * min(dr0, dc0)
    size = _heap_push(keys, gs, ids, 0, h0, 0.0, start)
    expansions = 0
    while size > 0:
        node, g, size = _heap_pop(keys, gs, ids, size)
        if closed[node]:
            continue
        closed[node] = True
        expansions += 1
        if node == goal:
            return parent, g, expansions
        r = node // width
        c = node - r * width
        for m in range(8):
            nb = node + offsets[m]
            if flat[nb] or closed[nb]:
                continue
            if m >= 4:
                # no corner cutting: both side cells must be free
                if flat[node + drs[m] * width] or flat[node + dcs[m]]:
                    continue
                ng = g + sqrt2
            else:
                ng = g + 1.0
            if use_cost:
                ng += cell_cost.ravel()[nb]
            if ng < g_best[nb]:
                g_best[nb] = ng
                parent[nb] = node
                dr = abs(r + drs[m] - gr)
                dc = abs(c + dcs[m] - gc)
                if dr > dc:
                    h = dr + diag_extra * dc
                else:
                    h = dc + diag_extra * dr
                size = _heap_push(keys, gs, ids, size, ng + h, ng, nb)
    return parent, -1.0, expansions


# ----------------------------------------------------------- pure Python
def _astar_python(blocked, sr, sc, gr, gc):
    height, width = blocked.shape
    g_best = {(sr, sc): 0.0}
    parent: dict = {}
    closed = set()
    heap = [(octile(sr - gr, sc - gc), 0.0, (sr, sc))]
    expansions = 0
    moves = [(int(dr), int(dc), SQRT2 if dr and dc else 1.0) for dr, dc in MOVES]
    while heap:
        _, neg_g, (r, c) = heapq.heappop(heap)
        if (r, c) in closed:
            continue
        closed.add((r, c))
        expansions += 1
        g = -neg_g
        if (r, c) == (gr, gc):
            return parent, g, expansions
        for dr, dc, step in moves:
            nr, nc = r + dr, c + dc
            if not (0 <= nr < height and 0 <= nc < width) or blocked[nr, nc]:
                continue
            if dr and dc and (blocked[nr, c] or blocked[r, nc]):
                continue
            ng = g + step
            if ng < g_best.get((nr, nc), math.inf) and (nr, nc) not in closed:
                g_best[(nr, nc)] = ng
                parent[(nr, nc)] = (r, c)
                heapq.heappush(heap, (ng + octile(nr - gr, nc - gc), -ng, (nr, nc)))
    return parent, -1.0, expansions


def _trace_flat(parent: np.ndarray, goal: int, width: int) -> np.ndarray:
    nodes = [goal]
    while parent[nodes[-1]] >= 0:
        nodes.append(int(parent[nodes[-1]]))
    nodes.reverse()
    flat = np.array(nodes, dtype=np.int64)
    return np.column_stack([flat // width, flat % width])


def _trace_dict(parent: dict, goal: tuple) -> np.ndarray:
    cells = [goal]
    while cells[-1] in parent:
        cells.append(parent[cells[-1]])
    cells.reverse()
    return np.array(cells, dtype=np.int64).reshape(-1, 2)


def astar_2d(occupied, start_cell, goal_cell, *, use_numba: bool = True, cell_cost=None) -> AStarResult:
    """Optimal 8-connected A* without corner cutting on a boolean occupancy array.

    ``cell_cost`` (optional, float >= 0, same shape) is added when entering a
    cell (numba kernel only), e.g. to keep a guide path away from narrow parts.
    """
    blocked = np.ascontiguousarray(occupied, dtype=np.bool_)
    if blocked.ndim != 2:
        raise ValueError(f"occupied must be 2-D, got shape {blocked.shape}")
    height, width = blocked.shape
    (sr, sc), (gr, gc) = (int(v) for v in start_cell), (int(v) for v in goal_cell)
    for name, (r, c) in (("start", (sr, sc)), ("goal", (gr, gc))):
        if not (0 <= r < height and 0 <= c < width):
            raise ValueError(f"{name} cell ({r}, {c}) is outside the {height} x {width} grid")
    empty = AStarResult(np.zeros((0, 2), dtype=np.int64), math.inf, 0)
    if blocked[sr, sc] or blocked[gr, gc]:
        return empty
    if use_numba and HAVE_NUMBA:
        padded = np.ones((height + 2, width + 2), dtype=np.bool_)
        padded[1:-1, 1:-1] = blocked
        use_cost = cell_cost is not None
        extra = np.zeros((1, 1)) if not use_cost else np.pad(np.asarray(cell_cost, dtype=float), 1)
        if use_cost and extra.shape != padded.shape:
            raise ValueError(f"cell_cost has shape {np.shape(cell_cost)}, occupied has {blocked.shape}")
        parent, cost, expansions = _astar_kernel(padded, sr + 1, sc + 1, gr + 1, gc + 1, extra, use_cost)
        if cost < 0:
            return empty._replace(expansions=int(expansions))
        path = _trace_flat(parent, (gr + 1) * (width + 2) + gc + 1, width + 2) - 1
        return AStarResult(path, float(cost), int(expansions))
    if cell_cost is not None:
        raise ValueError("cell_cost needs the numba kernel")
    parent, cost, expansions = _astar_python(blocked, sr, sc, gr, gc)
    if cost < 0:
        return empty._replace(expansions=expansions)
    return AStarResult(_trace_dict(parent, (gr, gc)), float(cost), expansions)


def path_cost(cells: np.ndarray) -> float:
    """Octile length of a cell path (straight 1, diagonal sqrt 2)."""
    cells = np.asarray(cells).reshape(-1, 2)
    if len(cells) < 2:
        return 0.0
    steps = np.abs(np.diff(cells, axis=0)).sum(axis=1)
    return float(np.sum(np.where(steps == 2, SQRT2, 1.0)))


class GridAStarPlanner:
    """2-D A* for a disc (or point) robot: obstacles grown by ``inflation_radius`` metres.

    With a polygonal footprint and no radius given, the radius is the
    footprint's circumradius, so the path is valid at any heading (headings are
    interpolated from the start's to the goal's along the path).
    """

    def __init__(self, footprint=None, inflation_radius: float | None = None):
        from maru_planner.base.se2 import footprint_radii

        if inflation_radius is None:
            inflation_radius = footprint_radii(footprint)[1] if footprint is not None else 0.0
        if not (math.isfinite(inflation_radius) and inflation_radius >= 0):
            raise ValueError(f"inflation_radius must be finite and >= 0, got {inflation_radius}")
        self.inflation_radius = float(inflation_radius)

    def plan(self, grid, start, goal):
        import time

        from maru_planner.base import common
        from maru_planner.base import result as R

        t0 = time.perf_counter()
        stats = {"expansions": 0, "collision_checks": 0, "planning_time": 0.0, "deciding_stage": "astar"}
        try:
            common.check_grid(grid)
            start, goal = common.as_pose(start, "start"), common.as_pose(goal, "goal")
            s_cell, g_cell = common.pose_cell(grid, start, "start"), common.pose_cell(grid, goal, "goal")
            grown = grid.inflate(self.inflation_radius) if self.inflation_radius > 0 else grid
            for name, pose, cell in (("start", start, s_cell), ("goal", goal, g_cell)):
                if grown.occupied[cell]:
                    raise common.occupied_error(name, pose, f"within {self.inflation_radius:.3f} m of an obstacle")
        except common.RequestError as exc:
            stats["planning_time"] = time.perf_counter() - t0
            return common.failure(exc.status, str(exc), stats)
        path, cost, expansions = astar_2d(grown.occupied, s_cell, g_cell)
        stats.update(expansions=expansions, collision_checks=8 * expansions, planning_time=time.perf_counter() - t0)
        layers = {"grown": grown.occupied}
        if len(path) == 0:
            return common.failure(R.NO_PATH, "no path: A* exhausted the free cells of the grown map", stats, layers)
        stats["cost"] = cost * grid.resolution
        return R.BasePlanResult(
            R.SOLVED, "solved by 2-D A*", common.cells_to_path(grid, path, start[2], goal[2]), stats, layers
        )
