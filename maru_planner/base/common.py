"""Request checks and path assembly shared by the grid planners (A*, SE(2) A*, MSPP, tunnel)."""

from __future__ import annotations

import math

import numpy as np

from maru_planner.base import result as R
from maru_planner.base.grid import OccupancyGrid


class RequestError(Exception):
    """A request problem with its BasePlanResult status (outside map, occupied, invalid)."""

    def __init__(self, status: str, message: str):
        super().__init__(message)
        self.status = status


def as_pose(pose, name: str) -> tuple[float, float, float]:
    """(x, y) or (x, y, theta), finite."""
    try:
        values = [float(v) for v in pose]
    except (TypeError, ValueError) as exc:
        raise RequestError(R.INVALID_REQUEST, f"{name} pose must be numbers (x, y, theta), got {pose!r}") from exc
    if len(values) == 2:
        values.append(0.0)
    if len(values) != 3:
        raise RequestError(R.INVALID_REQUEST, f"{name} pose must be (x, y, theta), got {len(values)} values")
    if not all(math.isfinite(v) for v in values):
        raise RequestError(R.INVALID_REQUEST, f"{name} pose has a NaN or infinite value: {values}")
    return values[0], values[1], values[2]


def pose_cell(grid: OccupancyGrid, pose, name: str) -> tuple[int, int]:
    """Cell of a pose; raises START_/GOAL_OUTSIDE_MAP."""
    row, col = grid.world_to_cell(pose[0], pose[1])
    if not grid.in_bounds(row, col):
        status = R.START_OUTSIDE_MAP if name == "start" else R.GOAL_OUTSIDE_MAP
        raise RequestError(
            status,
            f"{name} ({pose[0]:.3f}, {pose[1]:.3f}) is outside the map "
            f"({grid.width} x {grid.height} cells of {grid.resolution} m from origin {grid.origin[:2]})",
        )
    return row, col


def check_grid(grid) -> None:
    if grid is None:
        raise RequestError(R.INVALID_REQUEST, "no map")
    if grid.occupied.size == 0:
        raise RequestError(R.INVALID_REQUEST, "the map is empty (0 cells)")


def occupied_error(name: str, pose, what: str) -> RequestError:
    status = R.START_OCCUPIED if name == "start" else R.GOAL_OCCUPIED
    return RequestError(status, f"{name} ({pose[0]:.3f}, {pose[1]:.3f}, {pose[2]:.3f}) is in collision: {what}")


def disc_request(grid, start, goal, radius: float):
    """Check a request for a disc robot of ``radius`` on ``grid``; raises RequestError.

    Returns (start pose, goal pose, start cell, goal cell, grid grown by ``radius``).
    """
    check_grid(grid)
    start, goal = as_pose(start, "start"), as_pose(goal, "goal")
    s_cell, g_cell = pose_cell(grid, start, "start"), pose_cell(grid, goal, "goal")
    grown = grid.inflate(radius) if radius > 0 else grid
    for name, pose, cell in (("start", start, s_cell), ("goal", goal, g_cell)):
        if grown.occupied[cell]:
            raise occupied_error(name, pose, f"within {radius:.3f} m of an obstacle")
    return start, goal, s_cell, g_cell, grown


def wrap_angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def interpolate_headings(xy: np.ndarray, theta0: float, theta1: float) -> np.ndarray:
    """Headings along a polyline, turning from theta0 to theta1 in proportion to arc length."""
    n = len(xy)
    if n == 1:
        return np.array([theta1])
    seg = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    frac = s / s[-1] if s[-1] > 0 else np.linspace(0.0, 1.0, n)
    return theta0 + wrap_angle(theta1 - theta0) * frac


def cells_to_path(grid: OccupancyGrid, cells: np.ndarray, theta0: float, theta1: float) -> np.ndarray:
    """(n, 2) cells -> (n, 3) map-frame (x, y, theta) at cell centres, heading interpolated."""
    xy = grid.cells_to_world(cells)
    return np.column_stack([xy, interpolate_headings(xy, theta0, theta1)])


def states_to_path(grid: OccupancyGrid, states: np.ndarray, headings: int) -> np.ndarray:
    """(n, 3) SE(2) states (k, row, col) -> (n, 3) map-frame (x, y, theta)."""
    xy = grid.cells_to_world(states[:, 1:3])
    theta = np.array([wrap_angle(2 * math.pi * k / headings + grid.origin[2]) for k in states[:, 0]])
    return np.column_stack([xy, theta])


def failure(status: str, message: str, stats: dict, layers: dict | None = None) -> R.BasePlanResult:
    return R.BasePlanResult(status, message, np.zeros((0, 3)), stats, layers or {})
