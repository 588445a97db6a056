"""Multi-stage path planner (paper 002): ECA -> BAA -> full SE(2) A*.

1. **ECA** (enclosure check): obstacles grown by the footprint's inscribed
   radius about the reference point (half the minimum width of a centred
   robot). That disc lies inside the robot at every heading, so a grown cell
   is in collision at every heading; if the start and the goal are in
   different 8-connected components of the grown map's free cells, no path
   exists ("no path proven": the smaller side is reported as enclosed).
2. **BAA** (ball approximation): obstacles grown by the circumradius (half the
   maximum width). A free cell there is free at every heading, so a 2-D A*
   path there is a valid SE(2) path with any headings along it.
3. **full**: the complete SE(2) A* (``se2.py``).

:class:`LocalMultiStagePlanner` (``mspp_local``) is the "beyond the paper" variant its last paragraph asks
for: a guide path on the ECA map (steered away from BAA-blocked cells) is cut
into easy stretches (every cell and diagonal side cell BAA-free: any heading
is safe) and hard stretches; only the hard stretches get a full SE(2) A*, in a
window around them (any heading at their BAA-free ends). If a window search
fails, its window grows; when that also fails the full search runs over the
whole map, so the planner stays complete.

The cost layer is an option here (``cost_travel_multiplier`` > 0; the paper's plain searches by default):
BAA's 2-D A*, the full SE(2) A* and the local windows then minimise length plus the cost along the path;
ECA and the guide path of ``mspp_local`` stay as they are. With ``smooth``, a BAA path is smoothed on the
BAA map, an SE(2) path per run at one heading on its C-space layer.

Every stage is timed and counted in ``stats.stages`` (:class:`StageStats`);
``result.layers`` holds the grown maps (``eca``, ``baa``) and, for ``local``,
the guide and the windows.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from maru_planner.base.astar import astar_2d
from maru_planner.base.common import cells_to_path, interpolate_headings, states_to_path
from maru_planner.base.cost_model import CostSettings
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.planner import Endpoint, PlanRun
from maru_planner.base.result import PlanStats
from maru_planner.base.se2 import SE2AStarPlanner, cspace_layers, search_layers
from maru_planner.base.smoother import Stretch
from maru_planner.errors import InvalidRequest, NoPath, NoPathProven

# Keeps ECA strictly inside and BAA strictly outside the robot despite rounding.
RADIUS_GUARD = 1e-7


@dataclass
class WindowStats:
    """One windowed SE(2) search of ``mspp_local``: box (row0, col0, row1, col1) in cells."""

    box: list[int]
    cspace_cells: int
    expansions: int
    found: bool
    time: float


@dataclass
class StageStats:
    """One MSPP stage (ECA, BAA, full, local): what it cost and whether it decided."""

    name: str
    time: float = 0.0
    decided: bool = False
    expansions: int = 0
    collision_checks: int = 0
    radius: float | None = None
    skipped: str | None = None
    cost: float | None = None  # cells (full search)
    cspace_time: float | None = None
    cspace_cells: int | None = None
    search_time: float | None = None
    guide_expansions: int | None = None
    windows: list[WindowStats] | None = None
    fallback: str | None = None


@dataclass
class MultiStageStats(PlanStats):
    """PlanStats plus the footprint radii and one entry per stage (expansions/checks are their sums)."""

    headings: int = 0
    r_min: float = 0.0
    r_max: float = 0.0
    stages: list[StageStats] = field(default_factory=list)

    def add(self, stage: StageStats) -> StageStats:
        self.stages.append(stage)
        return stage

    def total(self) -> None:
        self.expansions = sum(s.expansions for s in self.stages)
        self.collision_checks = sum(s.collision_checks for s in self.stages)


class MultiStagePlanner(SE2AStarPlanner):
    """ECA -> BAA -> full SE(2) A*."""

    default_costs = CostSettings()

    def new_stats(self) -> PlanStats:
        return MultiStageStats(headings=self.headings, r_min=self.r_in, r_max=self.r_out)

    def search(self, space: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        try:
            self._eca(space, start, goal, run)
            path = self._baa(space, start, goal, run)
            if path is not None:
                return self._smooth_baa(space, path, start, goal, run)
            return self.smooth_states(space, self._last_stage(space, start, goal, run), run)
        finally:
            run.stats_as(MultiStageStats).total()

    def _smooth_baa(
        self, grid: OccupancyGrid, path: np.ndarray, start: Endpoint, goal: Endpoint, run: PlanRun
    ) -> np.ndarray:
        """A BAA path smoothed on the BAA map (any heading is free there), headings interpolated again."""
        layer = run.layers.get("costmap")
        if not self.costs.settings.smooth or layer is None or len(path) < 3:
            return path
        xy, info = self.costs.smooth(
            grid, path[:, :2], layer, [Stretch(0, len(path) - 1, run.layers["baa"])], run.deadline
        )
        run.stats.smoothing = info
        return np.column_stack([xy, interpolate_headings(xy, start.pose[2], goal.pose[2])])

    def _last_stage(self, grid: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        return self._full(grid, start, goal, run)

    # ---------------------------------------------------------------- stages
    def _eca(self, grid: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> None:
        t = time.perf_counter()
        stage = run.stats_as(MultiStageStats).add(StageStats("ECA", radius=self.r_in))
        run.monitor.report(stage.name)
        eca = grid.inflate(max(self.r_in - RADIUS_GUARD, 0.0), run.deadline).occupied
        labels, _ = ndimage.label(~eca, structure=np.ones((3, 3), dtype=int))
        ls, lg = labels[start.cell], labels[goal.cell]
        run.layers["eca"] = eca
        stage.collision_checks = int(eca.size)
        stage.time, stage.decided = time.perf_counter() - t, bool(ls != lg)
        if ls != lg:
            n_start, n_goal = int(np.sum(labels == ls)), int(np.sum(labels == lg))
            side, cells = ("start", n_start) if n_start <= n_goal else ("goal", n_goal)
            run.stats.deciding_stage = "ECA"
            raise NoPathProven(
                f"no path: {side} enclosed (obstacles grown by R_min = {self.r_in:.3f} m "
                f"leave it a region of {cells} cells)"
            )

    def _baa(self, grid: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray | None:
        t = time.perf_counter()
        stage = run.stats_as(MultiStageStats).add(StageStats("BAA", radius=self.r_out))
        run.monitor.report(stage.name)
        baa = grid.inflate(self.r_out + RADIUS_GUARD, run.deadline).occupied
        run.layers["baa"] = baa
        path = None
        if not baa[start.cell] and not baa[goal.cell]:
            cells, _, expansions = astar_2d(
                baa, start.cell, goal.cell, cell_weight=self.cost_weights(run), deadline=run.deadline
            )
            stage.expansions, stage.collision_checks = expansions, 8 * expansions
            if len(cells):
                run.stats.deciding_stage, run.message = "BAA", "solved by BAA"
                path = cells_to_path(grid, cells, start.pose[2], goal.pose[2])
        else:
            stage.skipped = "start or goal within R_max of an obstacle"
        stage.time, stage.decided = time.perf_counter() - t, path is not None
        return path

    def _full(self, grid: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        t = time.perf_counter()
        stage = run.stats_as(MultiStageStats).add(StageStats("full", decided=True))
        run.monitor.report(stage.name)
        run.stats.deciding_stage = "full"
        try:
            full = self.full_search(grid, start, goal, run.deadline, self.cost_weights(run))
        finally:
            stage.time = time.perf_counter() - t
        found = full.search
        stage.expansions, stage.collision_checks = found.expansions, found.collision_checks
        stage.cspace_time, stage.cspace_cells, stage.search_time = full.cspace_time, full.cspace_cells, full.search_time
        if not found.found:
            raise NoPath("no path: full SE(2) A* exhausted the free configurations")
        stage.cost = found.cost
        run.message = "solved by full search"
        return states_to_path(grid, found.states, self.headings)


class LocalMultiStagePlanner(MultiStagePlanner):
    """ECA -> BAA -> SE(2) A* only in windows around the guide path's hard runs (full search as fallback)."""

    def __init__(
        self,
        footprint,
        headings: int = 32,
        rotation_weight: float | None = None,
        local_margin: float | None = None,
        narrow_penalty: float = 4.0,
        **costs,
    ):
        super().__init__(footprint, headings, rotation_weight, **costs)
        self.local_margin = 2.0 * self.r_out if local_margin is None else float(local_margin)
        if not (math.isfinite(self.local_margin) and self.local_margin >= 0):
            raise InvalidRequest(f"local_margin must be finite and >= 0, got {local_margin}")
        if not (math.isfinite(narrow_penalty) and narrow_penalty >= 0):
            raise InvalidRequest(f"narrow_penalty must be finite and >= 0, got {narrow_penalty}")
        self.narrow_penalty = float(narrow_penalty)

    def _last_stage(self, grid: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        t = time.perf_counter()
        eca, baa = run.layers["eca"], run.layers["baa"]
        stage = run.stats_as(MultiStageStats).add(StageStats("local", windows=[]))
        run.monitor.report(stage.name)
        guide, _, guide_exp = astar_2d(
            eca, start.cell, goal.cell, cell_cost=baa * self.narrow_penalty, deadline=run.deadline
        )
        stage.guide_expansions = guide_exp
        pieces = None
        if len(guide):
            run.layers["guide"] = guide
            pieces = self._solve_hard_runs(grid, guide, baa, start, goal, stage, run)
        stage.time = time.perf_counter() - t
        if pieces is None:
            stage.fallback = "full search over the whole map"
            return self._full(grid, start, goal, run)
        stage.decided = True
        run.stats.deciding_stage, run.message = "local", "solved by BAA + local full search"
        return self._assemble(grid, pieces, start.pose, goal.pose)

    def _hard_runs(self, guide: np.ndarray, baa: np.ndarray) -> list[tuple[int, int]]:
        """Index ranges [a, b] of the guide whose steps are not safe at every heading."""
        free = ~baa[guide[:, 0], guide[:, 1]]
        easy = free[:-1] & free[1:]
        side1, side2 = baa[guide[1:, 0], guide[:-1, 1]], baa[guide[:-1, 0], guide[1:, 1]]
        easy &= ~(side1 | side2)
        runs, i = [], 0
        while i < len(easy):
            if easy[i]:
                i += 1
                continue
            j = i
            while j < len(easy) and not easy[j]:
                j += 1
            runs.append((i, j))  # steps i..j-1 hard: cells i..j
            i = j
        return runs

    def _solve_hard_runs(self, grid, guide, baa, start: Endpoint, goal: Endpoint, stage: StageStats, run: PlanRun):
        """SE(2) A* in a window around each hard run; None when a run cannot be solved locally."""
        sk, gk = self.heading_of(grid, start.pose), self.heading_of(grid, goal.pose)
        runs = self._merge_runs(self._hard_runs(guide, baa), guide, grid)
        pieces, last = [], 0
        windows = []
        for a, b in runs:
            pieces.append(("easy", guide[last : a + 1]))
            states = None
            for grow in (1, 2, 4):
                margin = int(math.ceil(grow * self.local_margin / grid.resolution))
                box = self._window(guide[a : b + 1], margin, grid.shape)
                states = self._window_search(
                    grid,
                    box,
                    guide[a],
                    guide[b],
                    sk if a == 0 else -1,
                    gk if b == len(guide) - 1 else -1,
                    baa,
                    stage,
                    run,
                )
                windows.append(box)
                if states is not None:
                    break
            if states is None:
                return None
            pieces.append(("hard", states))
            last = b
        pieces.append(("easy", guide[last:]))
        run.layers["windows"] = np.array(windows, dtype=int).reshape(-1, 4)
        return pieces

    def _merge_runs(self, runs, guide, grid):
        """Join consecutive hard runs whose windows overlap: one search instead of two over the same cells."""
        margin = int(math.ceil(self.local_margin / grid.resolution))
        merged: list[tuple[int, int]] = []
        for a, b in runs:
            if merged:
                pa, pb = merged[-1]
                r0, c0, r1, c1 = self._window(guide[pa : pb + 1], margin, grid.shape)
                q0, d0, q1, d1 = self._window(guide[a : b + 1], margin, grid.shape)
                if r0 < q1 and q0 < r1 and c0 < d1 and d0 < c1:
                    merged[-1] = (pa, b)
                    continue
            merged.append((a, b))
        return merged

    @staticmethod
    def _window(cells, margin, shape):
        r0, c0 = cells.min(axis=0) - margin
        r1, c1 = cells.max(axis=0) + margin + 1
        return max(r0, 0), max(c0, 0), min(r1, shape[0]), min(c1, shape[1])

    def _window_search(self, grid, box, entry, exit_, sk, gk, baa, stage: StageStats, run: PlanRun):
        r0, c0, r1, c1 = box
        t = time.perf_counter()
        window_layers = self._window_layers(grid, box, run)
        # A BAA-free end is safe at every heading (turning in place there is safe too).
        if sk >= 0 and baa[tuple(entry)]:
            starts = [(sk, entry[0] - r0, entry[1] - c0)]
        else:
            starts = [(k, entry[0] - r0, entry[1] - c0) for k in range(self.headings)]
        if gk >= 0 and not baa[tuple(exit_)]:
            gk = -1
        weights = self.cost_weights(run)
        out = search_layers(
            window_layers,
            starts,
            (exit_[0] - r0, exit_[1] - c0),
            gk,
            self.rot_cost_cells(grid.resolution),
            deadline=run.deadline,
            cell_weight=None if weights is None else weights[r0:r1, c0:c1],
        )
        stage.expansions += out.expansions
        stage.collision_checks += out.collision_checks
        assert stage.windows is not None  # the local stage is made with windows=[]
        stage.windows.append(
            WindowStats(
                [int(v) for v in box], int(window_layers.size), out.expansions, out.found, time.perf_counter() - t
            )
        )
        if not out.found:
            return None
        states = out.states.copy()
        states[:, 1] += r0
        states[:, 2] += c0
        return states

    def _window_layers(self, grid, box, run: PlanRun):
        """C-space layers of a window, seeing the obstacles just outside it."""
        r0, c0, r1, c1 = box
        offsets = self.offsets(grid, run.deadline)
        reach = max(int(np.max(np.abs(o))) if len(o) else 0 for o in offsets)
        R0, C0 = max(r0 - reach, 0), max(c0 - reach, 0)
        crop = grid.occupied[R0 : min(r1 + reach, grid.height), C0 : min(c1 + reach, grid.width)]
        layers = cspace_layers(crop, self.footprint, grid.resolution, self.headings, offsets, run.deadline)
        return np.ascontiguousarray(layers[:, r0 - R0 : r1 - R0, c0 - C0 : c1 - C0])

    def _assemble(self, grid, pieces, start, goal) -> np.ndarray:
        """Concatenate easy stretches (headings interpolated) and hard SE(2) stretches."""
        hard_paths = {i: states_to_path(grid, p, self.headings) for i, (kind, p) in enumerate(pieces) if kind == "hard"}
        out: list[np.ndarray] = []
        for i, (kind, cells) in enumerate(pieces):
            if kind == "hard":
                path = hard_paths[i]
            else:
                theta0 = start[2] if i == 0 else hard_paths[i - 1][-1, 2]
                theta1 = goal[2] if i == len(pieces) - 1 else hard_paths[i + 1][0, 2]
                path = cells_to_path(grid, cells, theta0, theta1)
            if out and len(path) and np.allclose(out[-1][-1, :2], path[0, :2]):
                # the shared cell: keep both headings (a turn in place, safe there)
                if np.isclose(out[-1][-1, 2], path[0, 2]):
                    path = path[1:]
            out.append(path)
        return np.concatenate([p for p in out if len(p)], axis=0)
