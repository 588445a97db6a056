"""Registry entries ``biped_track`` and ``biped_wall``: the biped planners on a 3-D world or on the node's grid.

``factory(footprint, world=None, **params).plan(grid, start, goal)``:

* with ``world`` (a 3-D world YAML path or a :class:`BipedWorld`) the 2-D map
  is the world's 3-D → 2-D mapping and the robot is the world's; ``grid`` may be
  None (the CLI's ``--world``) and is otherwise ignored;
* without it, ``grid`` is taken as an already mapped 2-D map (every occupied
  cell a line obstacle) and the gait rectangle is the footprint's bounding box
  (length along x, width along y; no body overhang).

Other keyword arguments are :class:`TrackParams` / :class:`WallParams` fields. A relative
``world`` path that does not exist is looked up under the package's ``config/``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from maru_planner.base.biped.mapping import BipedMap2D, map_3d_to_2d
from maru_planner.base.biped.space import BipedPlanner, BipedSpace
from maru_planner.base.biped.track import TrackFollowingPlanner
from maru_planner.base.biped.wall import VirtualWallPlanner
from maru_planner.base.biped.world import BipedRobot, BipedWorld, load_world
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.planner import Cell, Endpoint, GridPlanner, PlanRun, Pose, require_grid
from maru_planner.base.result import PlanStats
from maru_planner.errors import InvalidRequest
from maru_planner.paths import config_path


def robot_from_footprint(footprint) -> BipedRobot:
    pts = np.asarray(footprint, dtype=float).reshape(-1, 2)
    if len(pts) < 3:
        raise InvalidRequest("a biped planner needs a footprint polygon (its bounding box is the gait rectangle)")
    length, width = float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1]))
    if not (np.isfinite([length, width]).all() and length > 0 and width > 0):
        raise InvalidRequest(f"the footprint's bounding box must have a positive finite size, got {length} x {width}")
    return BipedRobot(gait_length=length, gait_width=width, body_left=width / 2, body_right=width / 2)


def map_from_grid(grid: OccupancyGrid) -> BipedMap2D:
    if abs(grid.origin[2]) > 1e-9:
        raise InvalidRequest("biped planners need a map whose origin yaw is 0")
    occupied = np.asarray(grid.occupied, dtype=bool)
    return BipedMap2D(occupied.copy(), np.zeros_like(occupied), grid.resolution, (grid.origin[0], grid.origin[1]))


def resolve_world_path(world) -> Path:
    path = Path(world)
    if not path.is_absolute() and not path.exists():
        candidate = config_path(*path.parts[1:]) if path.parts[0] == "config" else config_path(*path.parts)
        if candidate.exists():
            return candidate
    return path


class BipedGridPlanner(GridPlanner[BipedSpace]):
    """One of the two biped planners, on a 3-D world or on a plain grid (the skeleton steps delegate to it)."""

    KINDS: dict[str, Callable[..., BipedPlanner]] = {"track": TrackFollowingPlanner, "wall": VirtualWallPlanner}

    def __init__(self, kind: str, footprint=None, world: str | Path | BipedWorld | None = None, **params):
        if kind not in self.KINDS:
            raise InvalidRequest(f"unknown biped planner kind {kind!r}")
        self.kind = kind
        if isinstance(world, str | Path) and str(world):
            world = load_world(resolve_world_path(world))
        self.world: BipedWorld | None = world if isinstance(world, BipedWorld) else None
        self.map2d = map_3d_to_2d(self.world) if self.world is not None else None
        if self.world is not None:
            robot = self.world.robot
        else:
            robot = robot_from_footprint(footprint) if footprint is not None else BipedRobot()
        self.planner = self.KINDS[kind](robot, **params)

    def new_stats(self) -> PlanStats:
        stats = self.planner.new_stats()
        stats.mapping = "3d_world" if self.world is not None else "grid"
        return stats

    def prepare(self, grid: OccupancyGrid | None, run: PlanRun) -> BipedSpace:
        if self.world is not None:
            run.layers["world"] = self.world
        m = self.map2d if self.map2d is not None else map_from_grid(require_grid(grid))
        return self.planner.prepare(m, run)

    def collision(self, space: BipedSpace, pose: Pose, cell: Cell) -> str | None:
        return self.planner.collision(space, pose, cell)

    def search(self, space: BipedSpace, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        return self.planner.search(space, start, goal, run)


def biped_track(footprint=None, **params) -> BipedGridPlanner:
    return BipedGridPlanner("track", footprint, **params)


def biped_wall(footprint=None, **params) -> BipedGridPlanner:
    return BipedGridPlanner("wall", footprint, **params)


def world_defaults(world_path, start=None, goal=None):
    """For ``maru-base-plan --world``: (start, goal, resolved world path); start/goal default to the world's."""
    path = resolve_world_path(world_path)
    world = load_world(path)
    start = start if start is not None else world.start
    goal = goal if goal is not None else world.goal
    if start is None or goal is None:
        raise InvalidRequest(f"{path}: give --start/--goal, the world has none")
    return tuple(start), tuple(goal), str(path)
