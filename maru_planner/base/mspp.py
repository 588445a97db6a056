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

``local=True`` is the "beyond the paper" variant its last paragraph asks
for: a guide path on the ECA map (steered away from BAA-blocked cells) is cut
into easy stretches (every cell and diagonal side cell BAA-free: any heading
is safe) and hard stretches; only the hard stretches get a full SE(2) A*, in a
window around them (any heading at their BAA-free ends). If a window search
fails, its window grows; when that also fails the full search runs over the
whole map, so the planner stays complete.

Every stage is timed and counted in ``stats["stages"]``; ``result.layers``
holds the grown maps (``eca``, ``baa``) and, for ``local``, the windows.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import ndimage

from maru_planner.base import common
from maru_planner.base import result as R
from maru_planner.base.astar import astar_2d
from maru_planner.base.se2 import (
    SEARCH_FOUND,
    SEARCH_TIMED_OUT,
    SE2AStarPlanner,
    cspace_layers,
    search_layers,
)

# Keeps ECA strictly inside and BAA strictly outside the robot despite rounding.
RADIUS_GUARD = 1e-7


class MultiStagePlanner(SE2AStarPlanner):
    """ECA -> BAA -> full SE(2) A* (``local=False``) or windowed SE(2) A* (``local=True``)."""

    def __init__(
        self,
        footprint,
        headings: int = 32,
        rotation_weight: float | None = None,
        time_limit: float = 60.0,
        local: bool = False,
        local_margin: float | None = None,
        narrow_penalty: float = 4.0,
    ):
        super().__init__(footprint, headings, rotation_weight, time_limit)
        self.local = bool(local)
        self.local_margin = 2.0 * self.r_out if local_margin is None else float(local_margin)
        if not (math.isfinite(self.local_margin) and self.local_margin >= 0):
            raise ValueError(f"local_margin must be finite and >= 0, got {local_margin}")
        self.narrow_penalty = float(narrow_penalty)

    # ------------------------------------------------------------------ plan
    def plan(self, grid, start, goal):
        t0 = time.perf_counter()
        stats = {"expansions": 0, "collision_checks": 0, "planning_time": 0.0, "deciding_stage": "",
                 "headings": self.headings, "r_min": self.r_in, "r_max": self.r_out, "stages": []}
        layers: dict = {}
        try:
            s_cell, g_cell, sk, gk = self.check_endpoints(grid, start, goal)
        except common.RequestError as exc:
            stats["planning_time"] = time.perf_counter() - t0
            stats["deciding_stage"] = "validation"
            return common.failure(exc.status, str(exc), stats)
        start, goal = common.as_pose(start, "start"), common.as_pose(goal, "goal")

        decided = self._eca(grid, s_cell, g_cell, stats, layers)
        if decided is None:
            decided = self._baa(grid, start, goal, s_cell, g_cell, stats, layers)
        if decided is None:
            remaining = self.time_limit - (time.perf_counter() - t0)
            if self.local:
                decided = self._local(grid, start, goal, s_cell, g_cell, sk, gk, stats, layers, remaining)
            else:
                decided = self._full(grid, s_cell, g_cell, sk, gk, stats, remaining)
        status, message, path = decided
        stats["planning_time"] = time.perf_counter() - t0
        stats["expansions"] = sum(s.get("expansions", 0) for s in stats["stages"])
        stats["collision_checks"] = sum(s.get("collision_checks", 0) for s in stats["stages"])
        return R.BasePlanResult(status, message, path if path is not None else np.zeros((0, 3)), stats, layers)

    # ---------------------------------------------------------------- stages
    def _eca(self, grid, s_cell, g_cell, stats, layers):
        t = time.perf_counter()
        eca = grid.inflate(max(self.r_in - RADIUS_GUARD, 0.0)).occupied
        labels, _ = ndimage.label(~eca, structure=np.ones((3, 3), dtype=int))
        ls, lg = labels[s_cell], labels[g_cell]
        layers["eca"] = eca
        stage = {"name": "ECA", "radius": self.r_in, "collision_checks": int(eca.size), "expansions": 0}
        result = None
        if ls != lg:
            n_start, n_goal = int(np.sum(labels == ls)), int(np.sum(labels == lg))
            side, cells = ("start", n_start) if n_start <= n_goal else ("goal", n_goal)
            message = (f"no path: {side} enclosed (obstacles grown by R_min = {self.r_in:.3f} m "
                       f"leave it a region of {cells} cells)")
            stats["deciding_stage"] = "ECA"
            result = (R.NO_PATH_PROVEN, message, None)
        stage.update(time=time.perf_counter() - t, decided=result is not None)
        stats["stages"].append(stage)
        return result

    def _baa(self, grid, start, goal, s_cell, g_cell, stats, layers):
        t = time.perf_counter()
        baa = grid.inflate(self.r_out + RADIUS_GUARD).occupied
        layers["baa"] = baa
        stage = {"name": "BAA", "radius": self.r_out, "expansions": 0, "collision_checks": 0}
        result = None
        if not baa[s_cell] and not baa[g_cell]:
            cells, _, expansions = astar_2d(baa, s_cell, g_cell)
            stage.update(expansions=expansions, collision_checks=8 * expansions)
            if len(cells):
                stats["deciding_stage"] = "BAA"
                result = (R.SOLVED, "solved by BAA", common.cells_to_path(grid, cells, start[2], goal[2]))
        else:
            stage["skipped"] = "start or goal within R_max of an obstacle"
        stage.update(time=time.perf_counter() - t, decided=result is not None)
        stats["stages"].append(stage)
        return result

    def _full(self, grid, s_cell, g_cell, sk, gk, stats, time_limit):
        t = time.perf_counter()
        out = self.search(grid, s_cell, g_cell, sk, gk, time_limit)
        stats["deciding_stage"] = "full"
        stage = {"name": "full", "time": time.perf_counter() - t, "decided": True,
                 **{k: v for k, v in out.items() if k not in ("states", "status")}}
        stats["stages"].append(stage)
        if out["status"] == SEARCH_FOUND:
            return R.SOLVED, "solved by full search", common.states_to_path(grid, out["states"], self.headings)
        if out["status"] == SEARCH_TIMED_OUT:
            return R.TIMED_OUT, f"full SE(2) A* timed out after {stage['time']:.3f} s", None
        return R.NO_PATH, "no path: full SE(2) A* exhausted the free configurations", None

    # ------------------------------------------------------ local (beyond)
    def _local(self, grid, start, goal, s_cell, g_cell, sk, gk, stats, layers, time_limit):
        t = time.perf_counter()
        eca, baa = layers["eca"], layers["baa"]
        stage = {"name": "local", "expansions": 0, "collision_checks": 0, "windows": []}
        stats["stages"].append(stage)
        guide, _, guide_exp = astar_2d(eca, s_cell, g_cell, cell_cost=baa * self.narrow_penalty)
        stage["guide_expansions"] = guide_exp
        pieces = None
        if len(guide):
            layers["guide"] = guide
            pieces = self._solve_hard_runs(grid, guide, baa, sk, gk, stage, layers, t + time_limit)
        stage["time"] = time.perf_counter() - t
        if pieces is None:
            stage["decided"] = False
            stage["fallback"] = "full search over the whole map"
            return self._full(grid, s_cell, g_cell, sk, gk, stats, time_limit - stage["time"])
        stage["decided"] = True
        stats["deciding_stage"] = "local"
        return R.SOLVED, "solved by BAA + local full search", self._assemble(grid, pieces, start, goal)

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

    def _solve_hard_runs(self, grid, guide, baa, sk, gk, stage, layers, deadline):
        """SE(2) A* in a window around each hard run; None when a run cannot be solved locally."""
        runs = self._merge_runs(self._hard_runs(guide, baa), guide, grid)
        pieces, last = [], 0
        windows = []
        for a, b in runs:
            pieces.append(("easy", guide[last : a + 1]))
            states = None
            for grow in (1, 2, 4):
                margin = int(math.ceil(grow * self.local_margin / grid.resolution))
                box = self._window(guide[a : b + 1], margin, grid.shape)
                states = self._window_search(grid, box, guide[a], guide[b], sk if a == 0 else -1,
                                             gk if b == len(guide) - 1 else -1, baa, stage, deadline)
                windows.append(box)
                if states is not None:
                    break
            if states is None:
                return None
            pieces.append(("hard", states))
            last = b
        pieces.append(("easy", guide[last:]))
        layers["windows"] = np.array(windows, dtype=int).reshape(-1, 4)
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

    def _window_search(self, grid, box, entry, exit_, sk, gk, baa, stage, deadline):
        r0, c0, r1, c1 = box
        t = time.perf_counter()
        window_layers = self._window_layers(grid, box)
        # A BAA-free end is safe at every heading (turning in place there is safe too).
        if sk >= 0 and baa[tuple(entry)]:
            starts = [(sk, entry[0] - r0, entry[1] - c0)]
        else:
            starts = [(k, entry[0] - r0, entry[1] - c0) for k in range(self.headings)]
        if gk >= 0 and not baa[tuple(exit_)]:
            gk = -1
        out = search_layers(window_layers, starts, (exit_[0] - r0, exit_[1] - c0), gk,
                            self.rot_cost_cells(grid.resolution), time_limit=max(deadline - time.perf_counter(), 1e-3))
        stage["expansions"] += out["expansions"]
        stage["collision_checks"] += out["collision_checks"]
        stage["windows"].append({"box": [int(v) for v in box], "cspace_cells": int(window_layers.size),
                                 "expansions": out["expansions"], "found": out["status"] == SEARCH_FOUND,
                                 "time": time.perf_counter() - t})
        if out["status"] != SEARCH_FOUND:
            return None
        states = out["states"].copy()
        states[:, 1] += r0
        states[:, 2] += c0
        return states

    def _window_layers(self, grid, box):
        """C-space layers of a window, seeing the obstacles just outside it."""
        r0, c0, r1, c1 = box
        offsets = self.offsets(grid.resolution)
        reach = max(int(np.max(np.abs(o))) if len(o) else 0 for o in offsets)
        R0, C0 = max(r0 - reach, 0), max(c0 - reach, 0)
        crop = grid.occupied[R0 : min(r1 + reach, grid.height), C0 : min(c1 + reach, grid.width)]
        layers = cspace_layers(crop, self.footprint, grid.resolution, self.headings, offsets)
        return np.ascontiguousarray(layers[:, r0 - R0 : r1 - R0, c0 - C0 : c1 - C0])

    def _assemble(self, grid, pieces, start, goal) -> np.ndarray:
        """Concatenate easy stretches (headings interpolated) and hard SE(2) stretches."""
        hard_paths = [common.states_to_path(grid, p, self.headings) if kind == "hard" else None
                      for kind, p in pieces]
        out = []
        for i, (kind, cells) in enumerate(pieces):
            if kind == "hard":
                path = hard_paths[i]
            else:
                theta0 = start[2] if i == 0 else hard_paths[i - 1][-1, 2]
                theta1 = goal[2] if i == len(pieces) - 1 else hard_paths[i + 1][0, 2]
                path = common.cells_to_path(grid, cells, theta0, theta1)
            if out and len(path) and np.allclose(out[-1][-1, :2], path[0, :2]):
                # the shared cell: keep both headings (a turn in place, safe there)
                if np.isclose(out[-1][-1, 2], path[0, 2]):
                    path = path[1:]
            out.append(path)
        return np.concatenate([p for p in out if len(p)], axis=0)
