"""Heuristic tunnel planner (paper 003, Hyun 2014) on an occupancy grid.

The grid of small cells α is grouped into big cells β of ``b × b`` small
cells (the paper uses 3 × 3). Three processes run in turn:

* **TFP** (tunnel finding): from β_start, repeatedly add the 4-neighbour
  (Σ(β)) of the current β that minimises
  ``f_T = K1·f1 + K2·f2 + K3·f3`` (eq. 3-6; K1, K3 > 0, K2 < 0):
  f1 = distance to β_goal, f2 = distance from β_start (both divided by the
  β-grid diagonal ‖β_0 − β_N‖), f3 = fraction of obstacle cells in β, or
  ``maximum_value`` when β is full (never entered). The paper's loop has no
  rule for a dead end; ours backtracks along the chain to the last β with an
  unvisited neighbour (a greedy depth-first walk), so TFP fails only when
  no β chain exists. Every visited β belongs to the tunnel T.
* **LCRP** (lumped-cell removal): β ∈ T with 3+ Σ-neighbours in T are
  "lumped". Backtracking from β_goal to β_start inside T, always to a
  neighbour one step closer to β_start (breadth-first distances inside T),
  ties broken by ``f_L = K1·f_L1 + K2·f_L2`` (eq. 8-10) with the lumped
  cells as subgoals, gives the thin tunnel B (no β has 3+ B-neighbours).
* **PFP** (path finding): inside B, small cells are joined 8-neighbour (no
  corner cutting) by a greedy depth-first walk minimising
  ``f_P = (K4·‖α_sub − α‖ + K5·‖α_prev − α‖) / ‖α_0 − α_N‖`` (eq. 11;
  K4 > 0, K5 < 0) toward the centre α of the next β of B, then α_goal.

If PFP fails, β shrinks by one small cell per side and the three
processes run again; at ``min_big_cell_size`` the β connection where PFP
got stuck is recorded as a virtual obstacle (a blocked β–β edge) and TFP
runs again. With ``min_big_cell_size = 1`` the last round works on single
cells and finds a path whenever a 4-connected (= 8-connected without
corner cutting) free path exists.

The final path is the PFP cell chain shortened by line-of-sight
shortcuts between its cells (the paper's "turning points", ``line_of_sight.py``).

:class:`TunnelGridPlanner` is the registry's ``tunnel``: the planner on an ``OccupancyGrid`` grown by the robot's
radius. The cost layer is an option (``cost_travel_multiplier`` > 0; off by default, the paper's behaviour): the
line-of-sight shortcuts then never cross a cell costlier than the chain of cells they replace. ``smooth`` smooths the
waypoint path on the grown map (``smoother.py``).
"""

from __future__ import annotations

import dataclasses
import math
import time
from array import array
from dataclasses import dataclass, field

import numpy as np

from maru_planner.base.budget import Deadline, unlimited
from maru_planner.base.cost_model import CostSettings, split_cost_kwargs
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.line_of_sight import (  # noqa: F401 (segment_*: re-exported, their old home)
    segment_is_free,
    segment_max_cost,
    shortcut_cells,
)
from maru_planner.base.planner import DiscPlanner, Endpoint, PlanRun
from maru_planner.base.result import PlanStats, PlanStatus, status_of
from maru_planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidRequest,
    MaruError,
    NoPath,
    StartOccupied,
    StartOutsideMap,
)
from maru_planner.params import param

SIGMA = ((-1, 0), (0, 1), (1, 0), (0, -1))  # Σ(β): 4-neighbours (row, col)
GAMMA = ((-1, 0), (0, 1), (1, 0), (0, -1), (-1, -1), (-1, 1), (1, 1), (1, -1))  # Γ(α)


@dataclass
class TunnelParams:
    """Named parameters of the tunnel planner (the paper's signs enforced by ``validate``)."""

    big_cell_size: int = param(3, "side of a big cell β in small cells (the paper: 3)", lower=1, upper=64)
    min_big_cell_size: int = param(1, "smallest β side before virtual obstacles (1 = complete)", lower=1, upper=64)
    k1: float = param(1.0, "TFP/LCRP weight of the distance to the goal (> 0)", lower=0.0)
    k2: float = param(-0.2, "TFP/LCRP weight of the distance from the start (< 0)", upper=0.0)
    k3: float = param(0.05, "TFP weight of the obstacle fraction of β (> 0)", lower=0.0)
    k4: float = param(1.0, "PFP weight of the distance to the next subgoal (> 0)", lower=0.0)
    k5: float = param(-0.2, "PFP weight of the distance from the last subgoal (< 0)", upper=0.0)
    max_virtual_obstacles: int = param(200, "blocked β edges tried at the smallest size", lower=0, upper=100000)
    shortcut: bool = param(True, "keep only the turning points (line-of-sight shortcuts)")

    def validate(self) -> None:
        checks = [
            (self.big_cell_size >= 1, "big_cell_size must be >= 1"),
            (1 <= self.min_big_cell_size <= self.big_cell_size, "min_big_cell_size must be in [1, big_cell_size]"),
            (self.k1 > 0, "k1 must be > 0 (paper: K1 positive)"),
            (self.k2 < 0, "k2 must be < 0 (paper: K2 negative)"),
            (self.k3 > 0, "k3 must be > 0 (paper: K3 positive)"),
            (self.k4 > 0, "k4 must be > 0 (paper: K4 positive)"),
            (self.k5 < 0, "k5 must be < 0 (paper: K5 negative)"),
            (self.max_virtual_obstacles >= 0, "max_virtual_obstacles must be >= 0"),
        ]
        for ok, message in checks:
            if not ok:
                raise InvalidRequest(message)


@dataclass
class TunnelStats(PlanStats):
    """PlanStats plus the tunnel planner's counters (``expansions`` = TFP + PFP)."""

    tfp_expansions: int = 0
    lcrp_cells: int = 0
    pfp_expansions: int = 0
    attempts: int = 0
    virtual_obstacles: int = 0


@dataclass
class Attempt:
    """One TFP → LCRP → PFP round (kept for pictures and stats)."""

    big_cell_size: int
    failed_stage: str | None  # None = solved, "TFP" or "PFP"
    tunnel: np.ndarray  # (k, 2) β of T in visiting order
    lumped: np.ndarray  # (m, 2) lumped β
    thin_tunnel: np.ndarray  # (n, 2) β of B from start to goal
    cells: np.ndarray  # (p, 2) α path (PFP), empty on failure
    virtual_obstacles: list = field(default_factory=list)  # blocked β edges ((r, c), (r, c)) at this size
    failing_edge: tuple | None = None  # flat β pair where PFP got stuck


@dataclass
class CellPlan:
    """Tunnel planner answer in cell coordinates (row, col); ``error`` says why there is no path."""

    error: MaruError | None
    message: str
    raw_cells: np.ndarray  # PFP chain of small cells
    waypoints: np.ndarray  # shortcut turning points (row, col)
    attempts: list
    stats: TunnelStats

    @property
    def status(self) -> PlanStatus:
        return PlanStatus.SOLVED if self.error is None else status_of(self.error)


class BigCellGrid:
    """Small-cell grid seen as big cells of ``size × size`` (cells past the edge count as occupied).

    Big cells are addressed by flat index ``row * width + col``; ``full`` and
    ``count`` are bytes-like for fast scalar access from Python.
    """

    def __init__(self, occupied: np.ndarray, size: int):
        self.size = size
        h, w = occupied.shape
        self.grid_shape = (h, w)
        self.shape = (-(-h // size), -(-w // size))
        dtype = np.uint8 if size * size <= 255 else np.uint16
        # Counted one row of big cells at a time: no full-size copy of the map.
        self.obstacle_count = np.empty(self.shape, dtype=dtype)
        strip = np.ones((size, self.shape[1] * size), dtype=bool)
        for i in range(self.shape[0]):
            rows = occupied[i * size : (i + 1) * size]
            strip[:] = True
            strip[: len(rows), :w] = rows
            self.obstacle_count[i] = strip.reshape(size, self.shape[1], size).sum(axis=(0, 2))
        self.full = (self.obstacle_count == size * size).ravel().tobytes()
        self.count = self.obstacle_count.ravel().tolist() if dtype == np.uint16 else self.obstacle_count.tobytes()
        self.diagonal = max(float(np.hypot(self.shape[0] - 1, self.shape[1] - 1)), 1.0)

    def of(self, cell: tuple[int, int]) -> int:
        """Flat index of the big cell holding small cell (row, col)."""
        return (cell[0] // self.size) * self.shape[1] + cell[1] // self.size

    def rc(self, big: int) -> tuple[int, int]:
        return divmod(big, self.shape[1])

    def centre(self, big: int) -> tuple[int, int]:
        r, c = divmod(big, self.shape[1])
        half = self.size // 2
        return min(r * self.size + half, self.grid_shape[0] - 1), min(c * self.size + half, self.grid_shape[1] - 1)

    def neighbours(self, big: int):
        """Σ(β): flat indices of the 4-neighbours inside the grid."""
        w = self.shape[1]
        r, c = divmod(big, w)
        if r > 0:
            yield big - w
        if c < w - 1:
            yield big + 1
        if r < self.shape[0] - 1:
            yield big + w
        if c > 0:
            yield big - 1

    def to_rc(self, bigs) -> np.ndarray:
        """(k, 2) int32 (row, col) of flat indices."""
        flat = np.frombuffer(bigs, dtype=np.int32) if isinstance(bigs, array) else np.asarray(bigs, dtype=np.int32)
        out = np.empty((len(flat), 2), dtype=np.int32)
        np.floor_divide(flat, self.shape[1], out=out[:, 0])
        np.remainder(flat, self.shape[1], out=out[:, 1])
        return out


def _edge(a: int, b: int) -> tuple:
    return (a, b) if a <= b else (b, a)


def _dist(a, b) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


# --------------------------------------------------------------------------- TFP


def tunnel_finding(
    bg: BigCellGrid, start: int, goal: int, p: TunnelParams, blocked: set, deadline: Deadline
) -> tuple[array, bytearray, bool]:
    """TFP: greedy walk over Σ(β) minimising f_T, backtracking at dead ends.

    Returns (T in visiting order, T as a flat mask, reached_goal).
    """
    visited = bytearray(bg.shape[0] * bg.shape[1])
    visited[start] = 1
    tunnel = array("i", [start])
    chain = array("i", [start])  # 4 bytes per β, not a Python int object each
    full, count = bg.full, bg.count
    per_big = bg.size * bg.size
    g_rc, s_rc = bg.rc(goal), bg.rc(start)
    k1, k2, k3 = p.k1 / bg.diagonal, p.k2 / bg.diagonal, p.k3 / per_big
    while chain:
        deadline.check()
        cur = chain[-1]
        if cur == goal:
            return tunnel, visited, True
        best, best_f = -1, math.inf
        for nb in bg.neighbours(cur):
            if visited[nb] or full[nb] or (blocked and _edge(cur, nb) in blocked):
                continue  # a full β gets MAXIMUM_VALUE in eq. 6: never connected
            rc = bg.rc(nb)
            f = k1 * _dist(g_rc, rc) + k2 * _dist(s_rc, rc) + k3 * count[nb]
            if f < best_f:
                best, best_f = nb, f
        if best < 0:
            chain.pop()
            continue
        visited[best] = 1
        tunnel.append(best)
        chain.append(best)
    return tunnel, visited, False


# -------------------------------------------------------------------------- LCRP


def lumped_cells(tunnel: list) -> list:
    """β (row, col) of T with three or more Σ-neighbours in T."""
    members = set(tunnel)
    return [b for b in tunnel if sum((b[0] + dr, b[1] + dc) in members for dr, dc in SIGMA) >= 3]


def lumped_mask(mask: np.ndarray) -> np.ndarray:
    """Same on a 2-D bool mask of T (vectorised)."""
    m = mask.astype(np.uint8)
    n = np.zeros(mask.shape, dtype=np.uint8)
    n[1:] += m[:-1]
    n[:-1] += m[1:]
    n[:, 1:] += m[:, :-1]
    n[:, :-1] += m[:, 1:]
    return mask & (n >= 3)


def _bfs_depths(bg: BigCellGrid, members: bytearray, start: int, blocked: set) -> array:
    depth = array("i", [-1]) * len(members)
    depth[start] = 0
    frontier = [start]
    while frontier:
        nxt = []
        for cur in frontier:
            d = depth[cur] + 1
            for nb in bg.neighbours(cur):
                if members[nb] and depth[nb] < 0 and not (blocked and _edge(cur, nb) in blocked):
                    depth[nb] = d
                    nxt.append(nb)
        frontier = nxt
    return depth


def lumped_cell_removal(
    bg: BigCellGrid, members: bytearray, start: int, goal: int, p: TunnelParams, blocked: set
) -> tuple[list, np.ndarray]:
    """LCRP: backtrack from β_goal to β_start inside T; returns (B start→goal, lumped cells (k, 2))."""
    mask = np.frombuffer(bytes(members), dtype=np.uint8).reshape(bg.shape).astype(bool)
    lumped = np.flatnonzero(lumped_mask(mask)).astype(np.int32)
    del mask
    depth = _bfs_depths(bg, members, start, blocked)
    # Subgoals: the lumped cell met on the way back at each depth (smallest index on ties), as a
    # per-depth table: the walk goes down one depth per step, so the next subgoal is the first
    # entry below the current depth.
    depth_np = np.frombuffer(depth, dtype=np.int32)
    lumped_depth = depth_np[lumped]
    reachable = lumped_depth >= 0
    by_depth = np.full(max(depth[goal], 0) + 1, np.iinfo(np.int32).max, dtype=np.int32)
    inside = reachable & (lumped_depth <= depth[goal])
    np.minimum.at(by_depth, lumped_depth[inside], lumped[inside])
    none = np.iinfo(np.int32).max

    def next_subgoal_below(d: int) -> int:
        for k in range(d - 1, -1, -1):
            if by_depth[k] != none:
                return k
        return -1

    back = [goal]
    current_subgoal = bg.rc(goal)
    cur = goal
    pending = next_subgoal_below(depth[goal])  # depth of the next subgoal, -1 = β_start
    while cur != start:
        if pending >= depth[cur]:
            pending = next_subgoal_below(depth[cur])
        next_subgoal = bg.rc(int(by_depth[pending]) if pending >= 0 else start)
        best, best_f = -1, math.inf
        for nb in bg.neighbours(cur):
            if depth[nb] != depth[cur] - 1 or (blocked and _edge(cur, nb) in blocked):
                continue
            rc = bg.rc(nb)
            f = (p.k1 * _dist(next_subgoal, rc) + p.k2 * _dist(current_subgoal, rc)) / bg.diagonal
            if f < best_f:
                best, best_f = nb, f
        cur = best
        if pending >= 0 and cur == int(by_depth[pending]):
            current_subgoal = bg.rc(cur)
        back.append(cur)
    back.reverse()
    return back, bg.to_rc(lumped)


# --------------------------------------------------------------------------- PFP


def path_finding(
    occupied: np.ndarray, bg: BigCellGrid, thin: list, start: tuple, goal: tuple, p: TunnelParams, deadline: Deadline
):
    """PFP: greedy depth-first 8-neighbour walk of small cells inside B.

    Returns (cells or None, index in B of the β where the walk got stuck, expansions).
    """
    h, w = occupied.shape
    order = {b: i for i, b in enumerate(thin)}
    diag = max(float(np.hypot(h - 1, w - 1)), 1.0)
    k4, k5 = p.k4 / diag, p.k5 / diag
    last = len(thin) - 1
    visited = {start[0] * w + start[1]}
    chain = [start]
    progress = 0
    expansions = 0
    while chain:
        deadline.check()
        cur = chain[-1]
        if cur == goal:
            return chain, progress, expansions
        expansions += 1
        progress = max(progress, order[bg.of(cur)])
        target = goal if progress == last else bg.centre(thin[progress + 1])
        previous = start if progress == 0 else bg.centre(thin[progress])
        best, best_f = None, math.inf
        for dr, dc in GAMMA:
            r, c = cur[0] + dr, cur[1] + dc
            if not (0 <= r < h and 0 <= c < w) or occupied[r, c] or r * w + c in visited:
                continue
            if dr and dc and (occupied[cur[0] + dr, cur[1]] or occupied[cur[0], cur[1] + dc]):
                continue  # no corner cutting
            if bg.of((r, c)) not in order:
                continue
            f = k4 * _dist(target, (r, c)) + k5 * _dist(previous, (r, c))
            if f < best_f:
                best, best_f = (r, c), f
        if best is None:
            chain.pop()
            continue
        visited.add(best[0] * w + best[1])
        chain.append(best)
    return None, progress, expansions


# ----------------------------------------------------------------------- driver


def _as_array(items) -> np.ndarray:
    return np.asarray(list(items), dtype=int).reshape(-1, 2)


def _check_endpoint(occupied: np.ndarray, cell, name: str) -> None:
    h, w = occupied.shape
    if not (0 <= cell[0] < h and 0 <= cell[1] < w):
        raise (StartOutsideMap if name == "start" else GoalOutsideMap)(f"{name} cell {cell} outside map")
    if occupied[cell]:
        raise (StartOccupied if name == "start" else GoalOccupied)(f"{name} cell {cell} is occupied")


class TunnelPlanner:
    """Plans on a bool occupancy array (True = occupied, already grown by the robot radius)."""

    def __init__(self, params: TunnelParams | None = None, **overrides):
        unknown = set(overrides) - {f.name for f in dataclasses.fields(TunnelParams)}
        if unknown:
            raise InvalidRequest(f"unknown tunnel parameter(s) {sorted(unknown)}")
        self.params = dataclasses.replace(params or TunnelParams(), **overrides)
        self.params.validate()

    def plan_cells(
        self,
        occupied: np.ndarray,
        start,
        goal,
        deadline: Deadline | None = None,
        stats: TunnelStats | None = None,
        cost: np.ndarray | None = None,
    ) -> CellPlan:
        """Plan from cell ``start`` to ``goal``; fills ``stats`` (a fresh TunnelStats by default).

        ``cost`` (a cost layer's costs): the shortcuts never cross a cell costlier than the chain they replace.
        """
        occupied = np.asarray(occupied, dtype=bool)
        start, goal = (int(start[0]), int(start[1])), (int(goal[0]), int(goal[1]))
        t0 = time.perf_counter()
        stats = stats if stats is not None else TunnelStats()
        attempts: list[Attempt] = []
        try:
            for cell, name in ((start, "start"), (goal, "goal")):
                _check_endpoint(occupied, cell, name)
            return self._search(occupied, start, goal, attempts, stats, deadline or unlimited(), t0, cost)
        except MaruError as error:
            return self._finish(error, str(error), [], attempts, occupied, stats, t0, unlimited())

    def _search(self, occupied, start, goal, attempts, stats, deadline, t0, cost=None) -> CellPlan:
        p = self.params
        for size in range(p.big_cell_size, p.min_big_cell_size - 1, -1):
            bg = BigCellGrid(occupied, size)
            blocked: set = set()
            while True:
                attempt, cells = self._round(occupied, bg, start, goal, blocked, stats, deadline)
                attempts.append(attempt)
                if cells is not None:
                    return self._finish(
                        None,
                        f"path found with big cells of {size}×{size}",
                        cells,
                        attempts,
                        occupied,
                        stats,
                        t0,
                        deadline,
                        cost,
                    )
                if attempt.failed_stage == "TFP" or size > p.min_big_cell_size:
                    break
                if len(blocked) >= p.max_virtual_obstacles:
                    break
                blocked.add(attempt.failing_edge)
                stats.virtual_obstacles = len(blocked)
        last = attempts[-1] if attempts else None
        reason = f"{last.failed_stage} failed at big-cell size {last.big_cell_size}" if last else "no attempt"
        raise NoPath(f"no path: {reason}")

    def _round(self, occupied, bg: BigCellGrid, start, goal, blocked: set, stats: TunnelStats, deadline: Deadline):
        p = self.params
        stats.attempts += 1
        b_start, b_goal = bg.of(start), bg.of(goal)
        tunnel, members, reached = tunnel_finding(bg, b_start, b_goal, p, blocked, deadline)
        stats.tfp_expansions += len(tunnel)
        empty = np.zeros((0, 2), dtype=int)
        virtual = [tuple(map(bg.rc, e)) for e in sorted(blocked)]
        if not reached:
            return Attempt(bg.size, "TFP", bg.to_rc(tunnel), empty, empty, empty, virtual), None
        thin, lumped = lumped_cell_removal(bg, members, b_start, b_goal, p, blocked)
        del members
        stats.lcrp_cells += len(thin)
        cells, stuck, expansions = path_finding(occupied, bg, thin, start, goal, p, deadline)
        stats.pfp_expansions += expansions
        if cells is None:
            failing = _edge(thin[stuck], thin[min(stuck + 1, len(thin) - 1)])
            attempt = Attempt(
                bg.size, "PFP", bg.to_rc(tunnel), lumped, bg.to_rc(thin), empty, virtual + [tuple(map(bg.rc, failing))]
            )
            attempt.failing_edge = failing
            return attempt, None
        attempt = Attempt(bg.size, None, bg.to_rc(tunnel), lumped, bg.to_rc(thin), _as_array(cells), virtual)
        return attempt, cells

    def _finish(
        self, error, message, cells, attempts, occupied, stats: TunnelStats, t0, deadline, cost=None
    ) -> CellPlan:
        waypoints = cells
        if cells and self.params.shortcut:
            waypoints = shortcut_cells(occupied, cells, deadline, cost)
        stats.expansions = stats.tfp_expansions + stats.pfp_expansions
        stats.planning_time = time.perf_counter() - t0
        return CellPlan(error, message, _as_array(cells), _as_array(waypoints), attempts, stats)


# ------------------------------------------------ the registry's planner on an OccupancyGrid


def segment_headings(xy: np.ndarray, start_theta: float, goal_theta: float) -> np.ndarray:
    """θ of each pose along its outgoing segment; the ends keep the request's θ."""
    theta = np.empty(len(xy))
    if len(xy) > 1:
        d = np.diff(xy, axis=0)
        theta[:-1] = np.arctan2(d[:, 1], d[:, 0])
    if len(xy):
        theta[0] = start_theta
        theta[-1] = goal_theta
    return theta


def cells_to_path(grid, cells: np.ndarray, start_theta: float, goal_theta: float) -> np.ndarray:
    """(row, col) cells → (x, y, θ) rows; θ follows each segment, the ends keep the request's θ."""
    if len(cells) == 0:
        return np.zeros((0, 3))
    xy = grid.cells_to_world(cells)
    return np.column_stack([xy, segment_headings(xy, start_theta, goal_theta)])


class TunnelGridPlanner(DiscPlanner):
    """Registry entry ``tunnel``: the tunnel planner on an ``OccupancyGrid`` for a disc robot.

    Obstacles are grown by ``robot_radius`` metres (default: the footprint's
    circumradius, 0.25 m without a footprint — the paper's robot). Other
    keyword arguments are :class:`~maru_planner.base.tunnel.TunnelParams` fields and
    :class:`~maru_planner.base.cost_model.CostSettings` fields.
    """

    default_radius = 0.25

    def __init__(self, footprint=None, robot_radius: float | None = None, **params):
        costs, tunnel_params = split_cost_kwargs(params)
        super().__init__(robot_radius, footprint, CostSettings(**costs))
        self.planner = TunnelPlanner(**tunnel_params)

    @property
    def robot_radius(self) -> float:
        return self.radius

    def new_stats(self) -> PlanStats:
        return TunnelStats(deciding_stage="tunnel")

    def search(self, space: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        layer = run.layers.get("costmap")
        cost = layer.cost if layer is not None and self.costs.cost_aware else None
        plan = self.planner.plan_cells(
            space.occupied, start.cell, goal.cell, run.deadline, run.stats_as(TunnelStats), cost=cost
        )
        run.stats.collision_checks = run.stats.expansions
        last = plan.attempts[-1] if plan.attempts else None
        run.stats.deciding_stage = f"tunnel b={last.big_cell_size}" if last else "tunnel"
        run.layers.update(attempts=plan.attempts, raw_cells=plan.raw_cells, waypoints=plan.waypoints)
        if plan.error is not None:
            raise plan.error
        path = cells_to_path(space, plan.waypoints, start.pose[2], goal.pose[2])
        path[0, :2] = start.pose[:2]
        path[-1, :2] = goal.pose[:2]
        run.stats.cost = float(np.sum(np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1)))
        run.message = plan.message
        return self.smooth_path(space, path, run, lambda xy: segment_headings(xy, start.pose[2], goal.pose[2]))
