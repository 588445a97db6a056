"""What both biped planners search (a :class:`BipedMap2D` and its gait-rectangle checker) and their shared steps."""

from __future__ import annotations

from dataclasses import dataclass

from maru_planner.base.biped.geometry import RectangleChecker
from maru_planner.base.biped.mapping import BipedMap2D
from maru_planner.base.biped.world import BipedRobot
from maru_planner.base.planner import Cell, GridPlanner, PlanRun, Pose
from maru_planner.base.result import PlanStats
from maru_planner.errors import InvalidRequest


@dataclass
class BipedStats(PlanStats):
    """PlanStats plus where the 2-D map came from ("3d_world" or "grid"; set by the registry entries)."""

    mapping: str | None = None


class BipedSpace:
    """A biped map and the gait-rectangle checker on it (counts its checks)."""

    def __init__(self, m: BipedMap2D, robot: BipedRobot):
        self.map = m
        self.checker = RectangleChecker(m.occupied, m.resolution, m.origin, robot.gait_length, robot.gait_width)

    @property
    def resolution(self) -> float:
        return self.map.resolution

    @property
    def origin(self) -> tuple:
        return self.map.origin

    @property
    def shape(self) -> tuple[int, int]:
        return self.map.shape

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        return self.map.world_to_cell(x, y)


class BipedPlanner(GridPlanner[BipedSpace]):
    """Skeleton steps shared by track following and the virtual wall: the map is a BipedMap2D."""

    robot: BipedRobot

    def new_stats(self) -> BipedStats:
        return BipedStats()

    def prepare(self, grid: BipedMap2D | None, run: PlanRun) -> BipedSpace:
        if not isinstance(grid, BipedMap2D):
            raise InvalidRequest("no biped map (a BipedMap2D) to plan on")
        run.layers["map"] = grid
        return BipedSpace(grid, self.robot)

    def collision(self, space: BipedSpace, pose: Pose, cell: Cell) -> str | None:
        if space.checker.collides(*pose):
            return "the gait rectangle touches a line or virtual obstacle"
        return None
