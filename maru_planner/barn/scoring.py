"""The BARN Challenge's score, exactly as ``the-barn-challenge`` (HEAD bf5a226) computes it.

Per run: ``metric = 1_success * OT / clip(T, 2 OT, 8 OT)`` with OT = the challenge's path length / 2 m/s,
T = the time from the first 0.1 m of motion to arrival within 1 m of the goal, 100 s at most, any
collision a failure. For a grid outside the public set, OT comes from an 8-connected shortest path
on the generator's C-space (a cell is blocked if any cylinder lies in its 5 x 5 window) between the
challenge's start and goal cells of the full grid, as the dataset's README checks it. That is not the
generator's A* (45-degree turn limit, a cost penalty near obstacles): on the public worlds it gives
0.80 .. 1.06 (mean 0.96) times worlds.csv's OT, so a --grid run's metric is comparable, not identical.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from maru_planner.errors import NoPath
from maru_planner.physics.barn_world import CELL, full_grid

MOVE_THRESHOLD = 0.1  # m of motion that starts the clock
GOAL_RADIUS = 1.0  # m
TIME_LIMIT = 100.0  # s after the clock starts
OPTIMAL_SPEED = 2.0  # m/s
CLIP_LOW, CLIP_HIGH = 2.0, 8.0  # x OT (run.py since 2024-02-04)
FULL_START_CELL = (14, 19)  # (-2.25, 3) in the full grid
FULL_GOAL_CELL = (14, 86)  # (-2.25, 13)
ROBOT_CELLS = 2  # the generator's jackal_radius: 5 x 5 cells


def barn_metric(success: bool, time_s: float | None, optimal_time_s: float) -> float:
    """1_success * OT / clip(T, 2 OT, 8 OT)."""
    if not success or time_s is None:
        return 0.0
    return optimal_time_s / float(np.clip(time_s, CLIP_LOW * optimal_time_s, CLIP_HIGH * optimal_time_s))


def cspace(grid: np.ndarray) -> np.ndarray:
    """The generator's C-space of the full grid: blocked if any cylinder lies in the cell's 5 x 5 window."""
    # lazy: scipy.ndimage only for a --grid's OT (maru-barn --through-ros --world N starts faster without it)
    from scipy.ndimage import binary_dilation

    window = np.ones((2 * ROBOT_CELLS + 1, 2 * ROBOT_CELLS + 1), bool)
    return binary_dilation(full_grid(grid).astype(bool), structure=window)


def grid_optimal_time(grid: np.ndarray) -> float:
    """OT of any grid: the C-space shortest path from start to goal cell, in metres, / 2 m/s; NoPath if none."""
    # lazy: numba's A* kernels only for a --grid's OT (a 2-7 s import under load; public worlds have their OT)
    from maru_planner.base.astar import astar_2d

    blocked = cspace(grid)
    blocked[FULL_START_CELL] = blocked[FULL_GOAL_CELL] = False
    result = astar_2d(blocked, FULL_START_CELL, FULL_GOAL_CELL, method="astar")
    if len(result.path) == 0:
        raise NoPath("the grid has no free path for the robot (5 x 5-cell C-space): start and goal are not connected")
    steps = np.abs(np.diff(np.asarray(result.path), axis=0)).sum(axis=1)
    length = float(np.sum(np.where(steps == 2, math.sqrt(2), 1.0))) * CELL
    return length / OPTIMAL_SPEED


@dataclass
class RunTrace:
    """What a picture needs: the driven (true) trajectory, the last global path (world frame), contacts."""

    trajectory: np.ndarray
    global_path: np.ndarray
    contacts: list[tuple[float, float, float]]


@dataclass
class RunScore:
    """One run as the challenge records it (the ``--json`` fields under ``runs``)."""

    world: str
    seed: int
    success: bool
    collision: bool
    timeout: bool
    time_s: float | None
    optimal_time_s: float
    metric: float
    min_clearance_m: float
    sim_time_s: float
    wall_time_s: float
    cpu_time_s: float = 0.0  # this process's CPU time for the run (the wall clock counts other load too)
    cmd_timeouts: int = 0
    nan_commands: int = 0
    replans: int = 0

    def to_json(self) -> dict:
        values = asdict(self)
        for key in ("time_s", "metric", "min_clearance_m", "sim_time_s", "wall_time_s", "cpu_time_s"):
            if values[key] is not None:
                values[key] = round(float(values[key]), 4)
        return values


def summarise(runs: list[RunScore]) -> dict:
    """success/collision/timeout rates, the mean metric (mean over worlds of the mean over runs), real-time factor."""
    if not runs:
        return {"worlds": 0, "runs": 0}
    by_world: dict[str, list[float]] = {}
    for run in runs:
        by_world.setdefault(run.world, []).append(run.metric)
    sim, wall = sum(r.sim_time_s for r in runs), sum(r.wall_time_s for r in runs)
    cpu = sum(r.cpu_time_s for r in runs)
    done = [r.time_s for r in runs if r.success and r.time_s is not None]
    return {
        "worlds": len(by_world),
        "runs": len(runs),
        "success_rate": round(sum(r.success for r in runs) / len(runs), 4),
        "collision_rate": round(sum(r.collision for r in runs) / len(runs), 4),
        "timeout_rate": round(sum(r.timeout for r in runs) / len(runs), 4),
        "mean_metric": round(float(np.mean([np.mean(v) for v in by_world.values()])), 4),
        "mean_time_s": round(float(np.mean(done)), 3) if done else None,
        "realtime_factor": round(sim / wall, 2) if wall > 0 else None,
        "realtime_factor_cpu": round(sim / cpu, 2) if cpu > 0 else None,
    }


class RunJudge:
    """The challenge's clock and outcome from the ground truth, one control period at a time."""

    def __init__(self, start: tuple[float, float], goal: tuple[float, float], time_limit: float, max_wait: float):
        self.start, self.goal = start, goal
        self.time_limit, self.max_wait = time_limit, max_wait
        self.t_start: float | None = None
        self.outcome: str | None = None  # goal | collision | timeout, once decided

    def update(self, now: float, x: float, y: float, collided: bool) -> str | None:
        """The outcome once the run is over (goal, collision, timeout), else None."""
        if self.t_start is None and math.hypot(x - self.start[0], y - self.start[1]) >= MOVE_THRESHOLD:
            self.t_start = now
        if collided:
            self.outcome = "collision"
        elif math.hypot(x - self.goal[0], y - self.goal[1]) <= GOAL_RADIUS:
            self.outcome = "goal"
        elif (self.t_start is not None and now - self.t_start >= self.time_limit) or (
            self.t_start is None and now >= self.max_wait
        ):
            self.outcome = "timeout"
        return self.outcome

    def elapsed(self, now: float) -> float | None:
        return None if self.t_start is None else now - self.t_start
