"""SE(2) A* for a polygonal footprint on an occupancy grid (paper 002's complete planner).

Model (complete at its resolution):

- states are (heading index k, row, col): the reference point at a cell
  centre, heading ``k * 2 pi / K`` in the grid frame (``K`` = ``headings``,
  31 or 32 as in the paper);
- the robot at a state collides when the centre of an occupied cell lies in
  its footprint polygon (boundary included). The per-heading configuration-
  space obstacles are the grid dilated by the rotated, rasterised footprint
  (the "footprint convolution"), computed once per heading;
- moves: the 8 grid neighbours at the same heading (octile cost in metres; a
  diagonal also needs both side cells free at that heading, as in the 2-D
  A*), and turning in place to k +- 1 (cost ``rotation_weight * 2 pi / K``,
  metres per radian, default the footprint's circumradius: the arc of its
  farthest point);
- heuristic: octile distance + rotation_weight * angular distance to the goal
  heading. Translations never turn and turns never translate, so the sum is
  admissible and consistent; the first goal pop is optimal;
- cost-aware (``cost_travel_multiplier`` > 0, the default of ``se2``): a
  translation into a cell costs its length times ``1 + multiplier * cost / 252``
  with Nav2's inflation cost at the reference point (Smac's travel cost); turns
  in place keep their cost. The heuristic stays admissible: still optimal.

Stats (:class:`SE2Stats`): ``expansions`` (states popped), ``collision_checks``
(state look-ups in the C-space layers during the search), ``cspace_cells``
(cells x headings computed by the convolution), ``cspace_time``.

Budget: the search's memory is estimated before allocating (TooLarge over
``budget.MAX_SEARCH_BYTES``); rasterising, stamping and searching check the deadline.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numba
import numpy as np

from maru_planner.base.budget import Deadline, check_bytes, unlimited
from maru_planner.base.common import states_to_path
from maru_planner.base.cost_model import CostModel, CostSettings
from maru_planner.base.footprint import (
    as_polygon,
    footprint_radii,
    heading_index,
    heading_offsets,
    offsets_collide,
)
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.kernels import heap_grow, heap_pop, heap_push, now
from maru_planner.base.planner import Cell, Endpoint, GridPlanner, PlanRun, Pose, require_grid
from maru_planner.base.result import PlanStats
from maru_planner.base.smoother import Stretch, stretches_at_headings
from maru_planner.errors import InvalidRequest, NoPath, PlanningTimedOut

# Bytes per SE(2) state during a search: padded layer (1), g (8), parent (8), closed (1), C-space layer (1).
_BYTES_PER_STATE = 19
_TIMED_OUT = 2  # kernel outcome: 0 found, 1 exhausted, 2 timed out
DEFAULT_COST_TRAVEL_MULTIPLIER = 2.0  # Smac's default
_SMOOTH_MARGIN = 3  # cells around a stretch its smoothed vertices may use


def cspace_layers(
    occupied: np.ndarray,
    footprint,
    resolution: float,
    headings: int,
    offsets: list[np.ndarray] | None = None,
    deadline: Deadline | None = None,
) -> np.ndarray:
    """(K, H, W) bool: configuration-space obstacles for each heading k * 2 pi / K.

    Every occupied cell stamps the (reflected) footprint of each heading; the kernel checks
    ``deadline`` as it goes (PlanningTimedOut).
    """
    occupied = np.asarray(occupied, dtype=bool)
    deadline = deadline or unlimited()
    if offsets is None:
        offsets = heading_offsets(footprint, resolution, headings, occupied.shape, deadline)
    starts = np.cumsum([0] + [len(o) for o in offsets]).astype(np.int64)
    flat_offsets = np.concatenate([np.asarray(o, dtype=np.int64).reshape(-1, 2) for o in offsets])
    out = np.zeros((len(offsets),) + occupied.shape, dtype=np.bool_)
    if not _stamp_kernel(np.argwhere(occupied).astype(np.int64), flat_offsets, starts, out, deadline.kernel_at):
        deadline.raise_timeout(f"footprint C-space ({len(flat_offsets)} footprint cells over {headings} headings)")
    return out


@numba.njit(cache=True, nogil=True)
def _stamp_kernel(cells, offsets, starts, out, deadline_at):
    """out[k, r - dr, c - dc] = True for every occupied (r, c) and offset (dr, dc) of heading k.

    Returns False when the deadline passed before the end (checked every 64 offsets).
    """
    num_k, height, width = out.shape
    for k in range(num_k):
        layer = out[k]
        for j in range(starts[k], starts[k + 1]):
            if (j & 63) == 0 and now() > deadline_at[0]:
                return False
            dr = offsets[j, 0]
            dc = offsets[j, 1]
            for i in range(cells.shape[0]):
                r = cells[i, 0] - dr
                c = cells[i, 1] - dc
                if 0 <= r < height and 0 <= c < width:
                    layer[r, c] = True
    return True


@numba.njit(cache=True, nogil=True)
def _se2_kernel(blocked, starts, gr, gc, gk, rot_cost, deadline_at, initial_capacity, weights, use_weights):
    """A* over (k, r, c) on padded layers ``blocked`` (K, H, W; border blocked).

    ``starts``: (m, 3) start states (k, r, c) at cost 0; ``gk < 0`` accepts any
    goal heading. With ``use_weights`` a translation into cell (r, c) costs its
    length times ``1 + weights[r, c]`` (padded (H, W)). Returns (parent, goal
    state id or -1, cost, expansions, collision checks, status 0 found /
    1 exhausted / 2 timed out).
    """
    num_k, height, width = blocked.shape
    flat = blocked.ravel()
    wflat = weights.ravel()
    layer = height * width
    n = num_k * layer
    g_best = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    capacity = initial_capacity + starts.shape[0] + 1  # grows on demand (lazy duplicates)
    keys = np.empty(capacity)
    gs = np.empty(capacity)
    ids = np.empty(capacity, dtype=np.int64)
    sqrt2 = np.sqrt(2.0)
    diag_extra = sqrt2 - 1.0
    drs = np.array([0, 1, 0, -1, 1, 1, -1, -1])
    dcs = np.array([1, 0, -1, 0, 1, -1, 1, -1])
    size = 0
    checks = 0
    for i in range(starts.shape[0]):
        k, r, c = starts[i, 0], starts[i, 1], starts[i, 2]
        s = k * layer + r * width + c
        checks += 1
        if flat[s] or g_best[s] == 0.0:
            continue
        g_best[s] = 0.0
        dr = abs(r - gr)
        dc = abs(c - gc)
        h = max(dr, dc) + diag_extra * min(dr, dc)
        if gk >= 0:
            dk = abs(k - gk)
            h += rot_cost * min(dk, num_k - dk)
        size = heap_push(keys, gs, ids, size, h, 0.0, s)
    expansions = 0
    while size > 0:
        node, g, size = heap_pop(keys, gs, ids, size)
        if closed[node]:
            continue
        closed[node] = True
        expansions += 1
        if (expansions & 1023) == 0 and now() > deadline_at[0]:
            return parent, -1, g, expansions, checks, 2
        k = node // layer
        rem = node - k * layer
        r = rem // width
        c = rem - r * width
        if r == gr and c == gc and (gk < 0 or k == gk):
            return parent, node, g, expansions, checks, 0
        base = k * layer
        for m in range(10):
            if m < 8:
                nr = r + drs[m]
                nc = c + dcs[m]
                nk = k
                nb = base + nr * width + nc
                checks += 1
                if flat[nb] or closed[nb]:
                    continue
                if m >= 4:
                    checks += 2
                    if flat[base + nr * width + c] or flat[base + r * width + nc]:
                        continue
                    ng = g + sqrt2
                else:
                    ng = g + 1.0
                if use_weights:
                    ng = g + (sqrt2 if m >= 4 else 1.0) * (1.0 + wflat[nr * width + nc])
            else:
                nr = r
                nc = c
                nk = (k + (1 if m == 8 else num_k - 1)) % num_k
                nb = nk * layer + rem
                checks += 1
                if flat[nb] or closed[nb]:
                    continue
                ng = g + rot_cost
            if ng < g_best[nb]:
                g_best[nb] = ng
                parent[nb] = node
                dr = abs(nr - gr)
                dc = abs(nc - gc)
                h = max(dr, dc) + diag_extra * min(dr, dc)
                if gk >= 0:
                    dk = abs(nk - gk)
                    h += rot_cost * min(dk, num_k - dk)
                if size == keys.shape[0]:
                    keys, gs, ids = heap_grow(keys, gs, ids)
                size = heap_push(keys, gs, ids, size, ng + h, ng, nb)
    return parent, -1, 0.0, expansions, checks, 1


@dataclass
class LayerSearch:
    """Outcome of :func:`search_layers`: states (k, row, col) start → goal (empty when none), counts."""

    states: np.ndarray
    cost: float  # cells (inf without a path)
    expansions: int
    collision_checks: int

    @property
    def found(self) -> bool:
        return len(self.states) > 0


def check_search_memory(headings: int, height: int, width: int) -> None:
    """TooLarge when an SE(2) search over (headings, height, width) would not fit (padded layers, g, parent, closed)."""
    check_bytes(
        float(_BYTES_PER_STATE) * headings * (height + 2) * (width + 2),
        f"SE(2) A* over {headings} headings x {width} x {height} cells",
        "use fewer headings, a coarser map or mspp_local",
    )


def search_layers(
    layers: np.ndarray,
    starts,
    goal_cell: Cell,
    goal_k: int,
    rot_cost_cells: float,
    *,
    deadline: Deadline | None = None,
    initial_capacity: int | None = None,
    cell_weight: np.ndarray | None = None,
) -> LayerSearch:
    """Run the SE(2) A* on (K, H, W) C-space layers (unpadded; outside = blocked).

    ``starts``: iterable of (k, row, col); ``goal_k`` -1 = any heading; ``cell_weight`` (H, W), >= 0: a
    translation into a cell costs its length times ``1 + weight``. Raises PlanningTimedOut when
    ``deadline`` passes, TooLarge when the search would not fit in memory.
    """
    num_k, h, w = layers.shape
    check_search_memory(num_k, h, w)
    deadline = deadline or unlimited()
    padded = np.ones((num_k, h + 2, w + 2), dtype=np.bool_)
    padded[:, 1:-1, 1:-1] = layers
    starts = np.array([[k, r + 1, c + 1] for k, r, c in starts], dtype=np.int64).reshape(-1, 3)
    weights = np.zeros((1, 1)) if cell_weight is None else np.pad(np.asarray(cell_weight, dtype=float), 1)
    if cell_weight is not None and weights.shape != (h + 2, w + 2):
        raise ValueError(f"cell_weight has shape {np.shape(cell_weight)}, the layers {(h, w)}")
    parent, goal, cost, expansions, checks, status = _se2_kernel(
        padded,
        starts,
        int(goal_cell[0]) + 1,
        int(goal_cell[1]) + 1,
        int(goal_k),
        float(rot_cost_cells),
        deadline.kernel_at,
        int(initial_capacity if initial_capacity is not None else min(10 * padded.size, 1 << 20)),
        weights,
        cell_weight is not None,
    )
    if status == _TIMED_OUT:
        deadline.raise_timeout(f"SE(2) A* ({int(expansions)} expansions)")
    if goal < 0:
        return LayerSearch(np.zeros((0, 3), dtype=np.int64), math.inf, int(expansions), int(checks))
    ids = [int(goal)]
    while parent[ids[-1]] >= 0:
        ids.append(int(parent[ids[-1]]))
    flat = np.array(ids[::-1], dtype=np.int64)
    layer = (h + 2) * (w + 2)
    k, rem = flat // layer, flat % layer
    states = np.column_stack([k, rem // (w + 2) - 1, rem % (w + 2) - 1])
    return LayerSearch(states, float(cost), int(expansions), int(checks))


@dataclass
class SE2Stats(PlanStats):
    """PlanStats plus the C-space and search split of the full SE(2) A*."""

    headings: int = 0
    cspace_time: float | None = None
    cspace_cells: int | None = None
    search_time: float | None = None


@dataclass
class FullSearch:
    """A whole-map SE(2) A*: the search and how long the C-space and the search took."""

    search: LayerSearch
    cspace_time: float
    cspace_cells: int
    search_time: float


class SE2AStarPlanner(GridPlanner[OccupancyGrid]):
    """Complete SE(2) A* for a polygonal footprint (see the module docstring).

    The cost keywords are :class:`~maru_planner.base.cost_model.CostSettings` fields (default ``default_costs``:
    cost-aware here, the plain paper search for MSPP).
    """

    default_costs = CostSettings(cost_travel_multiplier=DEFAULT_COST_TRAVEL_MULTIPLIER)

    def __init__(self, footprint, headings: int = 32, rotation_weight: float | None = None, **costs):
        self.footprint = as_polygon(footprint)
        if not 1 <= int(headings) <= 3600:
            raise InvalidRequest(f"headings must be in [1, 3600], got {headings}")
        self.headings = int(headings)
        self.r_in, self.r_out = footprint_radii(self.footprint)
        self.rotation_weight = self.r_out if rotation_weight is None else float(rotation_weight)
        if not (math.isfinite(self.rotation_weight) and self.rotation_weight >= 0):
            raise InvalidRequest(f"rotation_weight must be finite and >= 0, got {rotation_weight}")
        self.costs = CostModel(dataclasses.replace(self.default_costs, **costs), self.r_in, self.r_out)
        self._offsets: dict[tuple, list[np.ndarray]] = {}

    def offsets(self, grid: OccupancyGrid, deadline: Deadline | None = None) -> list[np.ndarray]:
        """Rasterised footprint per heading for ``grid``'s resolution and size, cached."""
        key = (grid.resolution, grid.shape)
        if key not in self._offsets:
            self._offsets[key] = heading_offsets(self.footprint, grid.resolution, self.headings, grid.shape, deadline)
        return self._offsets[key]

    def rot_cost_cells(self, resolution: float) -> float:
        return self.rotation_weight * (2 * math.pi / self.headings) / resolution

    def heading_of(self, grid: OccupancyGrid, pose: Pose) -> int:
        return heading_index(grid.heading_to_grid(pose[2]), self.headings)

    def cost_weights(self, run: PlanRun) -> np.ndarray | None:
        """The search's per-cell weights at the reference point (None: the plain search)."""
        return self.costs.weights(run.layers.get("costmap"))

    # ----------------------------------------------------------- skeleton steps
    def new_stats(self) -> PlanStats:
        return SE2Stats(deciding_stage="full", headings=self.headings)

    def prepare(self, grid: OccupancyGrid | None, run: PlanRun) -> OccupancyGrid:
        grid = require_grid(grid)
        self.offsets(grid, run.deadline)
        if self.costs.needs_layer:
            run.layers["costmap"] = self.costs.layer(grid, run.deadline)
        return grid

    def collision(self, space: OccupancyGrid, pose: Pose, cell: Cell) -> str | None:
        offsets = self.offsets(space)[self.heading_of(space, pose)]
        return "the footprint covers an occupied cell" if offsets_collide(space.occupied, offsets, *cell) else None

    def search(self, space: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        full = self.full_search(space, start, goal, run.deadline, self.cost_weights(run))
        stats = run.stats_as(SE2Stats)
        stats.expansions, stats.collision_checks = full.search.expansions, full.search.collision_checks
        stats.cspace_time, stats.cspace_cells, stats.search_time = full.cspace_time, full.cspace_cells, full.search_time
        if not full.search.found:
            raise NoPath("no path: SE(2) A* exhausted the free configurations")
        stats.cost = full.search.cost * space.resolution
        run.message = "solved by full SE(2) A*"
        return self.smooth_states(space, states_to_path(space, full.search.states, self.headings), run)

    def full_search(
        self,
        grid: OccupancyGrid,
        start: Endpoint,
        goal: Endpoint,
        deadline: Deadline,
        cell_weight: np.ndarray | None = None,
    ) -> FullSearch:
        """C-space layers for the whole map, then the search (memory checked before either)."""
        check_search_memory(self.headings, *grid.shape)
        t = time.perf_counter()
        layers = cspace_layers(
            grid.occupied, self.footprint, grid.resolution, self.headings, self.offsets(grid, deadline), deadline
        )
        cspace_time = time.perf_counter() - t
        out = search_layers(
            layers,
            [(self.heading_of(grid, start.pose), *start.cell)],
            goal.cell,
            self.heading_of(grid, goal.pose),
            self.rot_cost_cells(grid.resolution),
            deadline=deadline,
            cell_weight=cell_weight,
        )
        return FullSearch(out, cspace_time, int(layers.size), time.perf_counter() - t)

    def smooth_states(self, grid: OccupancyGrid, path: np.ndarray, run: PlanRun) -> np.ndarray:
        """With ``smooth``: each run of poses at one heading smoothed on that heading's C-space (turns in place
        stay where they are, headings unchanged)."""
        layer = run.layers.get("costmap")
        if not self.costs.settings.smooth or layer is None or len(path) < 3:
            return path
        offsets = self.offsets(grid, run.deadline)
        try:
            stretches = [
                self._stretch(grid, path, first, last, offsets, run.deadline)
                for first, last in stretches_at_headings(path)
            ]
        except PlanningTimedOut:  # out of time after the search: the planned path stands
            run.stats.smoothing = {"stretches": 0, "sweeps": 0, "moved": 0, "accepted": False}
            return path
        xy, info = self.costs.smooth(grid, path[:, :2], layer, stretches, run.deadline)
        run.stats.smoothing = info
        return np.column_stack([xy, path[:, 2]])

    def _stretch(
        self, grid: OccupancyGrid, path: np.ndarray, first: int, last: int, offsets, deadline: Deadline
    ) -> Stretch:
        """The stretch's window (its cells + a margin) of the C-space layer at its heading."""
        k = heading_index(grid.heading_to_grid(path[first, 2]), self.headings)
        cells = np.array([grid.world_to_cell(x, y) for x, y in path[first : last + 1, :2]])
        (r0, c0), (r1, c1) = cells.min(axis=0) - _SMOOTH_MARGIN, cells.max(axis=0) + _SMOOTH_MARGIN + 1
        r0, c0, r1, c1 = max(r0, 0), max(c0, 0), min(r1, grid.height), min(c1, grid.width)
        reach = int(np.max(np.abs(offsets[k]))) if len(offsets[k]) else 0
        R0, C0 = max(r0 - reach, 0), max(c0 - reach, 0)
        crop = grid.occupied[R0 : min(r1 + reach, grid.height), C0 : min(c1 + reach, grid.width)]
        layer = cspace_layers(crop, self.footprint, grid.resolution, 1, [offsets[k]], deadline)[0]
        blocked = layer[r0 - R0 : r1 - R0, c0 - C0 : c1 - C0]
        return Stretch(first, last, blocked, (int(r0), int(c0)))
