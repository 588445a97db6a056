"""The base-planner contract (:class:`BasePlanner`) and the skeleton every planner of ``base/`` fills in.

:class:`GridPlanner.plan` is written once: it checks the poses, prepares the planner's map
(``prepare``), checks that start and goal lie inside it and are free (``collision``), runs
``search`` under the request's :class:`~maru_planner.base.budget.Deadline` and turns whatever
``MaruError`` a step raises into a failed :class:`BasePlanResult` (status from
:func:`~maru_planner.base.result.status_of`, the stats and layers gathered so far kept).

An optional :class:`~maru_planner.monitor.PlanMonitor` watches and cancels a plan. It gets the stages
("validation", "search" and what a planner reports through ``run.monitor``: MSPP's ECA, BAA, full,
local) and, when the search ends, the expansions. Its ``cancel()`` terminates the request's deadline,
so the next deadline check (Python loops and numba kernels alike) stops the plan, as CANCELLED.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Generic, Protocol, TypeVar

import numpy as np

from maru_planner.base.budget import DEFAULT_TIME_LIMIT, Deadline
from maru_planner.base.cost_model import CostModel, CostSettings
from maru_planner.base.footprint import footprint_radii
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import BasePlanResult, PlanStats, PlanStatus, empty_path, status_of
from maru_planner.base.smoother import Stretch
from maru_planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidRequest,
    MaruError,
    StartOccupied,
    StartOutsideMap,
)
from maru_planner.monitor import PlanMonitor

Pose = tuple[float, float, float]
Cell = tuple[int, int]


class BasePlanner(Protocol):
    """What the registry's factories build: ``plan`` a path for one request within ``time_limit`` seconds.

    ``monitor`` (optional) receives progress and can cancel the plan from another thread.
    """

    def plan(
        self,
        grid: OccupancyGrid | None,
        start: Sequence[float],
        goal: Sequence[float],
        *,
        time_limit: float = DEFAULT_TIME_LIMIT,
        monitor: PlanMonitor | None = None,
    ) -> BasePlanResult: ...


class PlanningMap(Protocol):
    """What the skeleton needs of a planner's map: its cells and where a point falls."""

    @property
    def resolution(self) -> float: ...

    @property
    def shape(self) -> tuple[int, int]: ...

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]: ...


@dataclass(frozen=True)
class Endpoint:
    """A checked start or goal: its name, map-frame pose and cell."""

    name: str
    pose: Pose
    cell: Cell


StatsT = TypeVar("StatsT", bound=PlanStats)


@dataclass
class PlanRun:
    """What one ``plan`` call accumulates: its deadline, stats and drawable layers (kept on failure).

    ``monitor`` takes a planner's own stages (``run.monitor.report("BAA")``); cancelling it ends the deadline.
    """

    deadline: Deadline
    stats: PlanStats
    layers: dict[str, Any] = field(default_factory=dict)
    message: str = ""
    monitor: PlanMonitor = field(default_factory=PlanMonitor)

    def stats_as(self, kind: type[StatsT]) -> StatsT:
        """The stats as the planner's own ``PlanStats`` subclass (the one its ``new_stats`` returns)."""
        if not isinstance(self.stats, kind):
            raise TypeError(f"the run's stats are {type(self.stats).__name__}, not {kind.__name__}")
        return self.stats


def as_pose(pose: Sequence[float], name: str) -> Pose:
    """(x, y) or (x, y, theta), finite; InvalidRequest naming ``name`` otherwise."""
    try:
        values = [float(v) for v in pose]
    except (TypeError, ValueError):
        raise InvalidRequest(f"{name} pose must be numbers (x, y, theta), got {str(pose)[:60]}") from None
    if len(values) == 2:
        values.append(0.0)
    if len(values) != 3:
        raise InvalidRequest(f"{name} pose must be (x, y, theta), got {len(values)} values")
    if not all(math.isfinite(v) for v in values):
        raise InvalidRequest(f"{name} pose has a NaN or infinite value: {values}")
    return values[0], values[1], values[2]


def require_grid(grid: OccupancyGrid | None) -> OccupancyGrid:
    """The grid, or InvalidRequest when there is none or it has no cells."""
    if grid is None:
        raise InvalidRequest("no map")
    if grid.occupied.size == 0:
        raise InvalidRequest("the map is empty (0 cells)")
    return grid


MapT = TypeVar("MapT", bound=PlanningMap)


class GridPlanner(ABC, Generic[MapT]):
    """Skeleton of a base planner (see the module doc); subclasses give the four steps."""

    def plan(
        self,
        grid: Any,
        start: Sequence[float],
        goal: Sequence[float],
        *,
        time_limit: float = DEFAULT_TIME_LIMIT,
        monitor: PlanMonitor | None = None,
    ) -> BasePlanResult:
        t0 = time.perf_counter()
        stats: PlanStats = self.new_stats()
        layers: dict[str, Any] = {}
        path = empty_path()
        monitor = monitor or PlanMonitor()
        try:
            run = PlanRun(Deadline(time_limit), stats, layers, monitor=monitor)
            with monitor.attach(run.deadline):
                path = self._plan(run, grid, start, goal)
            status, message = PlanStatus.SOLVED, run.message
        except MaruError as error:
            status, message = status_of(error), str(error)
        stats.planning_time = time.perf_counter() - t0
        return BasePlanResult(status, message, path, stats, layers)

    def _plan(self, run: PlanRun, grid: Any, start: Sequence[float], goal: Sequence[float]) -> np.ndarray:
        run.monitor.report("validation")
        poses = as_pose(start, "start"), as_pose(goal, "goal")
        space = self.prepare(grid, run)
        ends = [self._endpoint(space, pose, name) for pose, name in zip(poses, ("start", "goal"), strict=True)]
        run.monitor.report("search")
        path = self.search(space, ends[0], ends[1], run)
        run.monitor.report(run.monitor.stage, expansions=run.stats.expansions)
        return path

    def _endpoint(self, space: MapT, pose: Pose, name: str) -> Endpoint:
        cell = space.world_to_cell(pose[0], pose[1])
        height, width = space.shape
        if not (0 <= cell[0] < height and 0 <= cell[1] < width):
            error = StartOutsideMap if name == "start" else GoalOutsideMap
            origin = getattr(space, "origin", (0.0, 0.0))
            raise error(
                f"{name} ({pose[0]:.3f}, {pose[1]:.3f}) is outside the map ({width} x {height} cells of "
                f"{space.resolution} m from origin ({origin[0]:g}, {origin[1]:g}))"
            )
        reason = self.collision(space, pose, cell)
        if reason:
            occupied = StartOccupied if name == "start" else GoalOccupied
            raise occupied(f"{name} ({pose[0]:.3f}, {pose[1]:.3f}, {pose[2]:.3f}) is in collision: {reason}")
        return Endpoint(name, pose, cell)

    def new_stats(self) -> PlanStats:
        """Fresh stats for one request (planners with their own counters return their subclass)."""
        return PlanStats()

    @abstractmethod
    def prepare(self, grid: Any, run: PlanRun) -> MapT:
        """The map this planner searches, built from the request's ``grid`` (may record layers)."""

    @abstractmethod
    def collision(self, space: MapT, pose: Pose, cell: Cell) -> str | None:
        """Why the robot at ``pose`` (in ``cell``) collides, or None when it is free."""

    @abstractmethod
    def search(self, space: MapT, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        """The (n, 3) path from start to goal; raises NoPath/NoPathProven/PlanningTimedOut/TooLarge."""


class DiscPlanner(GridPlanner[OccupancyGrid]):
    """A disc robot of ``radius`` metres on the grid grown by that radius (astar, tunnel).

    Without a radius the disc is the ``footprint``'s circumcircle, or ``default_radius`` without either.
    ``costs`` (:class:`~maru_planner.base.cost_model.CostSettings`; default ``default_costs``) adds Nav2's
    inflation costs (inscribed and circumscribed radii: the footprint's, or both the disc's radius when one
    is given) and the smoother; the cost layer is computed with the grown map from one distance transform.
    """

    default_radius = 0.0
    default_costs = CostSettings()

    def __init__(self, radius: float | None, footprint: Any = None, costs: CostSettings | None = None):
        if radius is None and footprint is not None:
            inscribed, radius = footprint_radii(footprint)
        else:
            radius = self.default_radius if radius is None else radius
            inscribed = radius
        if not (isinstance(radius, int | float) and math.isfinite(radius) and radius >= 0):
            raise InvalidRequest(f"robot radius must be finite and >= 0 m, got {radius}")
        self.radius = float(radius)
        self.costs = CostModel(costs or self.default_costs, min(inscribed, self.radius), self.radius)

    def prepare(self, grid: OccupancyGrid | None, run: PlanRun) -> OccupancyGrid:
        grid = require_grid(grid)
        if self.costs.needs_layer:
            layer = self.costs.layer(grid, run.deadline, reach=self.radius)
            grown = grid.with_occupied(layer.distance <= self.radius + 1e-9 * grid.resolution)
            run.layers["costmap"] = layer
        else:
            grown = grid.inflate(self.radius, run.deadline)
        run.layers["grown"] = grown.occupied
        return grown

    def collision(self, space: OccupancyGrid, pose: Pose, cell: Cell) -> str | None:
        return f"within {self.radius:.3f} m of an obstacle" if space.occupied[cell] else None

    def cost_weights(self, run: PlanRun) -> np.ndarray | None:
        """The search's per-cell weights (None: the plain shortest path)."""
        return self.costs.weights(run.layers.get("costmap"))

    def smooth_path(self, space: OccupancyGrid, path: np.ndarray, run: PlanRun, headings) -> np.ndarray:
        """``path`` smoothed as one stretch on the grown map when ``smooth`` is set; ``headings(xy)`` re-heads it."""
        layer = run.layers.get("costmap")
        if not self.costs.settings.smooth or layer is None or len(path) < 3:
            return path
        xy, info = self.costs.smooth(
            space, path[:, :2], layer, [Stretch(0, len(path) - 1, space.occupied)], run.deadline
        )
        run.stats.smoothing = info
        return np.column_stack([xy, headings(xy)])
