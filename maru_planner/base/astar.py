"""2-D grid A*: 8-connected, octile costs, no corner cutting, optimal.

API (used by ``mspp.py``, ``tunnel.py`` and the benchmarks)::

    path, cost, expansions = astar_2d(occupied, start_cell, goal_cell)

- ``occupied``: bool array ``(height, width)`` (row = y, col = x), e.g.
  ``grid.occupied`` or ``grid.inflate(r).occupied``.
- ``start_cell``, ``goal_cell``: ``(row, col)``; outside the map -> ValueError.
- returns an :class:`AStarResult` (a NamedTuple, so it unpacks as above):
  ``path`` int array ``(n, 2)`` of (row, col) from start to goal (empty
  ``(0, 2)`` when there is no path or start/goal is occupied), ``cost`` in
  cells (straight 1, diagonal sqrt 2; ``inf`` without a path), ``expansions``.
- ``cell_weight`` (optional, >= 0 per cell): a step into a cell costs its
  length times ``1 + weight`` (Smac 2D's travel cost; the cost layer gives
  the weights), so the search minimises length plus the cost along the path.

A diagonal move needs both side cells free (the MovingAI convention), so the
octile heuristic is consistent and the first pop of the goal is optimal. Ties
on f are broken towards larger g. The kernels are compiled with numba
(``cache=True``) and check the deadline every 4096 expansions.
"""

from __future__ import annotations

import dataclasses
import math
import threading
from typing import NamedTuple

import numba
import numpy as np

from maru_planner.base.budget import Deadline, unlimited
from maru_planner.base.common import cells_to_path, interpolate_headings
from maru_planner.base.cost_model import CostSettings
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.kernels import heap_grow, heap_pop, heap_push, now
from maru_planner.base.planner import DiscPlanner, Endpoint, PlanRun
from maru_planner.base.result import PlanStats
from maru_planner.errors import NoPath

SQRT2 = math.sqrt(2.0)
DEFAULT_COST_TRAVEL_MULTIPLIER = 2.0  # Smac 2D's default
_EXHAUSTED, _TIMED_OUT = -1.0, -2.0  # kernel "costs" that are outcomes


class AStarResult(NamedTuple):
    path: np.ndarray
    cost: float
    expansions: int


def _njit(func):
    return numba.njit(cache=True, nogil=True)(func)


@_njit
def _astar_kernel(
    blocked, sr, sc, gr, gc, cell_cost, cost_mode, g_best, parent, seen, closed, keys, gs, ids, gen, deadline_at
):
    """A* on a grid padded with one blocked cell on every side.

    ``blocked`` is the padded (height + 2, width + 2) array; cells are given in
    padded coordinates. Returns (parent array over padded cells, goal cost or
    -1 exhausted / -2 timed out, expansions, heap arrays). ``cost_mode`` 1:
    entering a cell adds ``cell_cost`` (padded, >= 0) to the move cost; 2: it
    multiplies the move's length by ``1 + cell_cost``. Either way the octile
    heuristic stays admissible and consistent.
    """
    height, width = blocked.shape
    flat = blocked.ravel()
    cflat = cell_cost.ravel()
    sqrt2 = np.sqrt(2.0)
    diag_extra = sqrt2 - 1.0
    drs = np.array([0, 1, 0, -1, 1, 1, -1, -1])
    dcs = np.array([1, 0, -1, 0, 1, -1, 1, -1])
    offsets = drs * width + dcs
    start = sr * width + sc
    goal = gr * width + gc
    g_best[start] = 0.0
    seen[start] = gen
    parent[start] = -1
    dr0 = abs(sr - gr)
    dc0 = abs(sc - gc)
    h0 = max(dr0, dc0) + diag_extra * min(dr0, dc0)
    size = heap_push(keys, gs, ids, 0, h0, 0.0, start)
    expansions = 0
    while size > 0:
        node, g, size = heap_pop(keys, gs, ids, size)
        if closed[node] == gen:
            continue
        closed[node] = gen
        expansions += 1
        if node == goal:
            return parent, g, expansions, keys, gs, ids
        if (expansions & 4095) == 0 and now() > deadline_at[0]:
            return parent, -2.0, expansions, keys, gs, ids
        r = node // width
        c = node - r * width
        for m in range(8):
            nb = node + offsets[m]
            if flat[nb] or closed[nb] == gen:
                continue
            if m >= 4:
                # no corner cutting: both side cells must be free
                if flat[node + drs[m] * width] or flat[node + dcs[m]]:
                    continue
                ng = g + sqrt2
            else:
                ng = g + 1.0
            if cost_mode == 1:
                ng += cflat[nb]
            elif cost_mode == 2:
                ng = g + (sqrt2 if m >= 4 else 1.0) * (1.0 + cflat[nb])
            if seen[nb] != gen or ng < g_best[nb]:
                g_best[nb] = ng
                seen[nb] = gen
                parent[nb] = node
                dr = abs(r + drs[m] - gr)
                dc = abs(c + dcs[m] - gc)
                if dr > dc:
                    h = dr + diag_extra * dc
                else:
                    h = dc + diag_extra * dr
                if size == keys.shape[0]:
                    keys, gs, ids = heap_grow(keys, gs, ids)
                size = heap_push(keys, gs, ids, size, ng + h, ng, nb)
    return parent, -1.0, expansions, keys, gs, ids


@_njit
def _jump_straight(flat, node, step, side, goal):
    """Scan from ``node`` along ``step``; the first cell with a forced neighbour (or the goal), else -1.

    ``side`` is the offset to the cells beside the line. Without corner
    cutting, a side cell is forced when it is free and the cell before it
    (beside the previous cell on the line) is blocked.
    """
    while True:
        node += step
        if flat[node]:
            return -1
        if node == goal:
            return node
        if (not flat[node + side] and flat[node + side - step]) or (not flat[node - side] and flat[node - side - step]):
            return node


@_njit
def _jump_diagonal(flat, node, step_r, step_c, goal):
    """Scan diagonally; stop where a straight scan along either component finds a jump point."""
    while True:
        if flat[node + step_r] or flat[node + step_c]:
            return -1
        node += step_r + step_c
        if flat[node]:
            return -1
        if node == goal:
            return node
        if _jump_straight(flat, node, step_r, step_c, goal) >= 0:
            return node
        if _jump_straight(flat, node, step_c, step_r, goal) >= 0:
            return node


@_njit
def _jps_kernel(blocked, sr, sc, gr, gc, g_best, parent, seen, closed, keys, gs, ids, gen, deadline_at):
    """Jump point search (8-connected, no corner cutting; Harabor & Grastien 2014) on a padded grid.

    Returns (parent array over padded cells (jump points only), goal cost or -1 / -2 as in
    ``_astar_kernel``, expansions, heap arrays).
    """
    height, width = blocked.shape
    flat = blocked.ravel()
    sqrt2 = np.sqrt(2.0)
    diag_extra = sqrt2 - 1.0
    start = sr * width + sc
    goal = gr * width + gc
    g_best[start] = 0.0
    seen[start] = gen
    parent[start] = -1
    dr0 = abs(sr - gr)
    dc0 = abs(sc - gc)
    size = heap_push(keys, gs, ids, 0, max(dr0, dc0) + diag_extra * min(dr0, dc0), 0.0, start)
    expansions = 0
    dirs_r = np.empty(8, dtype=np.int64)
    dirs_c = np.empty(8, dtype=np.int64)
    while size > 0:
        node, g, size = heap_pop(keys, gs, ids, size)
        if closed[node] == gen:
            continue
        closed[node] = gen
        expansions += 1
        if node == goal:
            return parent, g, expansions, keys, gs, ids
        if (expansions & 4095) == 0 and now() > deadline_at[0]:
            return parent, -2.0, expansions, keys, gs, ids
        r = node // width
        c = node - r * width
        # directions to scan: all 8 at the start, else the natural + forced ones
        count = 0
        if parent[node] < 0:
            for a in range(-1, 2):
                for b in range(-1, 2):
                    if a != 0 or b != 0:
                        dirs_r[count] = a
                        dirs_c[count] = b
                        count += 1
        else:
            pr = parent[node] // width
            pc = parent[node] - pr * width
            dr = int(r > pr) - int(r < pr)
            dc = int(c > pc) - int(c < pc)
            if dr != 0 and dc != 0:
                dirs_r[0], dirs_c[0] = dr, 0
                dirs_r[1], dirs_c[1] = 0, dc
                dirs_r[2], dirs_c[2] = dr, dc
                count = 3
            elif dr == 0:
                dirs_r[0], dirs_c[0] = 0, dc
                count = 1
                for s in (-1, 1):
                    if not flat[node + s * width] and flat[node + s * width - dc]:
                        dirs_r[count], dirs_c[count] = s, 0
                        dirs_r[count + 1], dirs_c[count + 1] = s, dc
                        count += 2
            else:
                dirs_r[0], dirs_c[0] = dr, 0
                count = 1
                for s in (-1, 1):
                    if not flat[node + s] and flat[node + s - dr * width]:
                        dirs_r[count], dirs_c[count] = 0, s
                        dirs_r[count + 1], dirs_c[count + 1] = dr, s
                        count += 2
        for i in range(count):
            a = dirs_r[i]
            b = dirs_c[i]
            if a != 0 and b != 0:
                jp = _jump_diagonal(flat, node, a * width, b, goal)
            elif a != 0:
                jp = _jump_straight(flat, node, a * width, 1, goal)
            else:
                jp = _jump_straight(flat, node, b, width, goal)
            if jp < 0 or closed[jp] == gen:
                continue
            jr = jp // width
            jc = jp - jr * width
            ar = abs(jr - r)
            ac = abs(jc - c)
            ng = g + (ar if ar > ac else ac) + diag_extra * (ac if ar > ac else ar)
            if seen[jp] != gen or ng < g_best[jp]:
                g_best[jp] = ng
                seen[jp] = gen
                parent[jp] = node
                hr = abs(jr - gr)
                hc = abs(jc - gc)
                h = (hr if hr > hc else hc) + diag_extra * (hc if hr > hc else hr)
                if size == keys.shape[0]:
                    keys, gs, ids = heap_grow(keys, gs, ids)
                size = heap_push(keys, gs, ids, size, ng + h, ng, jp)
    return parent, -1.0, expansions, keys, gs, ids


@_njit
def _trace_kernel(parent, start, goal, width, fill):
    """Cells (padded row, col) from start to goal; ``fill`` walks the straight/diagonal segments between jump points."""
    count = 1
    node = goal
    while node != start:
        prev = parent[node]
        if fill:
            a = abs(node // width - prev // width)
            b = abs(node % width - prev % width)
            count += a if a > b else b
        else:
            count += 1
        node = prev
    out = np.empty((count, 2), dtype=np.int64)
    i = count - 1
    node = goal
    out[i, 0] = node // width
    out[i, 1] = node % width
    while node != start:
        prev = parent[node]
        r, c = node // width, node % width
        pr, pc = prev // width, prev % width
        if fill:
            sr = int(pr > r) - int(pr < r)
            sc = int(pc > c) - int(pc < c)
            while r != pr or c != pc:
                r += sr
                c += sc
                i -= 1
                out[i, 0] = r
                out[i, 1] = c
        else:
            i -= 1
            out[i, 0] = pr
            out[i, 1] = pc
        node = prev
    return out


class _Workspace:
    """Per-thread search arrays reused across queries (a generation stamp replaces clearing them).

    The heap starts small and doubles in the kernels when full; the grown arrays are kept.
    """

    _local = threading.local()

    def __init__(self, n: int):
        self.n = n
        self.g = np.empty(n)
        self.parent = np.empty(n, dtype=np.int64)
        self.seen = np.zeros(n, dtype=np.int32)
        self.closed = np.zeros(n, dtype=np.int32)
        capacity = min(8 * n + 1, 1 << 16)
        self.keys, self.gs, self.ids = np.empty(capacity), np.empty(capacity), np.empty(capacity, dtype=np.int64)
        self.gen = 0

    @classmethod
    def get(cls, n: int) -> _Workspace:
        ws = getattr(cls._local, "ws", None)
        if ws is None or ws.n != n:
            ws = cls._local.ws = cls(n)
        ws.gen += 1
        if ws.gen >= 2**31 - 1:
            ws.seen[:] = 0
            ws.closed[:] = 0
            ws.gen = 1
        return ws

    def arrays(self) -> tuple:
        return self.g, self.parent, self.seen, self.closed, self.keys, self.gs, self.ids, self.gen

    def keep_heap(self, keys: np.ndarray, gs: np.ndarray, ids: np.ndarray) -> None:
        self.keys, self.gs, self.ids = keys, gs, ids


def astar_2d(
    occupied,
    start_cell,
    goal_cell,
    *,
    cell_cost=None,
    cell_weight=None,
    method: str = "jps",
    deadline: Deadline | None = None,
) -> AStarResult:
    """Optimal 8-connected A* without corner cutting on a boolean occupancy array.

    ``method``: "jps" (default; jump point search: the same optimal cost with
    far fewer heap operations, ``expansions`` counts jump points) or "astar"
    (plain A*, every cell). ``cell_cost`` or ``cell_weight`` always use plain A*.

    ``cell_cost`` (optional, float >= 0, same shape) is added when entering a
    cell, e.g. to keep a guide path away from narrow parts. ``cell_weight``
    (optional, float >= 0, same shape): entering a cell costs the step's length
    times ``1 + weight`` (the cost returned is then that sum, in cells). Raises
    PlanningTimedOut when ``deadline`` passes during the search.
    """
    blocked = np.ascontiguousarray(occupied, dtype=np.bool_)
    if method not in ("jps", "astar"):
        raise ValueError(f"method must be 'jps' or 'astar', got {method!r}")
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
    deadline = deadline or unlimited()
    padded = np.ones((height + 2, width + 2), dtype=np.bool_)
    padded[1:-1, 1:-1] = blocked
    args = (padded, sr + 1, sc + 1, gr + 1, gc + 1)
    ws = _Workspace.get(padded.size)
    if cell_cost is not None and cell_weight is not None:
        raise ValueError("give cell_cost or cell_weight, not both")
    weighted = cell_cost if cell_cost is not None else cell_weight
    jps = weighted is None and method == "jps"
    if weighted is not None:
        extra = np.pad(np.asarray(weighted, dtype=float), 1)
        if extra.shape != padded.shape:
            raise ValueError(f"cell costs have shape {np.shape(weighted)}, occupied has {blocked.shape}")
        out = _astar_kernel(*args, extra, 1 if cell_cost is not None else 2, *ws.arrays(), deadline.kernel_at)
    elif method == "astar":
        out = _astar_kernel(*args, np.zeros((1, 1)), 0, *ws.arrays(), deadline.kernel_at)
    else:
        out = _jps_kernel(*args, *ws.arrays(), deadline.kernel_at)
    parent, cost, expansions = out[:3]
    ws.keep_heap(*out[3:])
    if cost == _TIMED_OUT:
        deadline.raise_timeout(f"2-D A* ({int(expansions)} expansions)")
    if cost == _EXHAUSTED:
        return empty._replace(expansions=int(expansions))
    wp = width + 2
    path = _trace_kernel(parent, (sr + 1) * wp + sc + 1, (gr + 1) * wp + gc + 1, wp, jps) - 1
    return AStarResult(path, float(cost), int(expansions))


def path_cost(cells: np.ndarray) -> float:
    """Octile length of a cell path (straight 1, diagonal sqrt 2)."""
    cells = np.asarray(cells).reshape(-1, 2)
    if len(cells) < 2:
        return 0.0
    steps = np.abs(np.diff(cells, axis=0)).sum(axis=1)
    return float(np.sum(np.where(steps == 2, SQRT2, 1.0)))


class GridAStarPlanner(DiscPlanner):
    """2-D A* for a disc (or point) robot: obstacles grown by ``robot_radius`` metres, Nav2's costs by default.

    With a polygonal footprint and no radius given, the radius is the
    footprint's circumradius, so the path is valid at any heading (headings are
    interpolated from the start's to the goal's along the path). The cost
    keywords are :class:`~maru_planner.base.cost_model.CostSettings` fields;
    ``cost_travel_multiplier=0`` plans the plain shortest path (JPS).
    """

    default_costs = CostSettings(cost_travel_multiplier=DEFAULT_COST_TRAVEL_MULTIPLIER)

    def __init__(self, footprint=None, robot_radius: float | None = None, **costs):
        super().__init__(robot_radius, footprint, dataclasses.replace(self.default_costs, **costs))

    @property
    def robot_radius(self) -> float:
        return self.radius

    def new_stats(self) -> PlanStats:
        return PlanStats(deciding_stage="astar")

    def search(self, space: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        stats = run.stats
        weights = self.cost_weights(run)
        path, cost, expansions = astar_2d(
            space.occupied, start.cell, goal.cell, cell_weight=weights, deadline=run.deadline
        )
        stats.expansions, stats.collision_checks = expansions, 8 * expansions
        if len(path) == 0:
            raise NoPath("no path: A* exhausted the free cells of the grown map")
        stats.cost = cost * space.resolution
        run.message = "solved by 2-D A*" + (" (cost-aware)" if weights is not None else "")
        poses = cells_to_path(space, path, start.pose[2], goal.pose[2])
        return self.smooth_path(space, poses, run, lambda xy: interpolate_headings(xy, start.pose[2], goal.pose[2]))
