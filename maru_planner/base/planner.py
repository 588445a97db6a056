"""The base-planner contract (:class:`BasePlanner`) and the skeleton every planner of ``base/`` fills in.

:class:`GridPlanner.plan` is written once: it checks the poses, prepares the planner's map
(``prepare``), checks that start and goal lie inside it and are free (``collision``), runs
``search`` under the request's :class:`~maru_planner.base.budget.Deadline` and turns whatever
``MaruError`` a step raises into a failed :class:`BasePlanResult` (status from
:func:`~maru_planner.base.result.status_of`, the stats and layers gathered so far kept).
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
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import BasePlanResult, PlanStats, PlanStatus, empty_path, status_of
from maru_planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidRequest,
    MaruError,
    StartOccupied,
    StartOutsideMap,
)

Pose = tuple[float, float, float]
Cell = tuple[int, int]


class BasePlanner(Protocol):
    """What the registry's factories build: ``plan`` a path for one request within ``time_limit`` seconds."""

    def plan(
        self,
        grid: OccupancyGrid | None,
        start: Sequence[float],
        goal: Sequence[float],
        *,
        time_limit: float = DEFAULT_TIME_LIMIT,
    ) -> BasePlanResult: ...


class PlanningMap(Protocol):
    """What the skeleton needs of a planner's map: its cells and where a point falls."""

    resolution: float

    @property
    def shape(self) -> tuple[int, int]: ...

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]: ...


@dataclass(frozen=True)
class Endpoint:
    """A checked start or goal: its name, map-frame pose and cell."""

    name: str
    pose: Pose
    cell: Cell


@dataclass
class PlanRun:
    """What one ``plan`` call accumulates: its deadline, stats and drawable layers (kept on failure)."""

    deadline: Deadline
    stats: PlanStats
    layers: dict[str, Any] = field(default_factory=dict)
    message: str = ""


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
    ) -> BasePlanResult:
        t0 = time.perf_counter()
        stats: PlanStats = self.new_stats()
        layers: dict[str, Any] = {}
        path = empty_path()
        try:
            run = PlanRun(Deadline(time_limit), stats, layers)
            poses = as_pose(start, "start"), as_pose(goal, "goal")
            space = self.prepare(grid, run)
            ends = [self._endpoint(space, pose, name) for pose, name in zip(poses, ("start", "goal"), strict=True)]
            path = self.search(space, ends[0], ends[1], run)
            status, message = PlanStatus.SOLVED, run.message
        except MaruError as error:
            status, message = status_of(error), str(error)
        stats.planning_time = time.perf_counter() - t0
        return BasePlanResult(status, message, path, stats, layers)

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
            error = StartOccupied if name == "start" else GoalOccupied
            raise error(f"{name} ({pose[0]:.3f}, {pose[1]:.3f}, {pose[2]:.3f}) is in collision: {reason}")
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
    """A disc robot of ``radius`` metres on the grid grown by that radius (astar, tunnel)."""

    def __init__(self, radius: float):
        if not (math.isfinite(radius) and radius >= 0):
            raise InvalidRequest(f"robot radius must be finite and >= 0 m, got {radius}")
        self.radius = float(radius)

    def prepare(self, grid: OccupancyGrid | None, run: PlanRun) -> OccupancyGrid:
        grown = require_grid(grid).inflate(self.radius, run.deadline)
        run.layers["grown"] = grown.occupied
        return grown

    def collision(self, space: OccupancyGrid, pose: Pose, cell: Cell) -> str | None:
        return f"within {self.radius:.3f} m of an obstacle" if space.occupied[cell] else None
