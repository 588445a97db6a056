"""Message <-> core conversions for base_planner_node (nav_msgs maps, poses, paths, error codes)."""

from __future__ import annotations

import json
import math

import numpy as np
from geometry_msgs.msg import Point32, PoseStamped
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from nav_msgs.msg import Path

from maru_planner.base.costmap import CostLayer, to_occupancy_values
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import PlanStats, PlanStatus, status_of
from maru_planner.errors import InvalidMap, InvalidPlanner, InvalidRequest, MaruError
from maru_planner_interfaces.srv import PlanBasePath

E = PlanBasePath.Response
# The one place base-planning statuses become PlanBasePath error codes.
STATUS_TO_ERROR = {
    PlanStatus.SOLVED: E.NONE,
    PlanStatus.NO_PATH: E.NO_VALID_PATH,
    PlanStatus.NO_PATH_PROVEN: E.NO_PATH_PROVEN,
    PlanStatus.START_OCCUPIED: E.START_OCCUPIED,
    PlanStatus.GOAL_OCCUPIED: E.GOAL_OCCUPIED,
    PlanStatus.START_OUTSIDE_MAP: E.START_OUTSIDE_MAP,
    PlanStatus.GOAL_OUTSIDE_MAP: E.GOAL_OUTSIDE_MAP,
    PlanStatus.TIMED_OUT: E.TIMEOUT,
    PlanStatus.CANCELLED: E.UNKNOWN,  # PlanBasePath has no cancel code: the action goal ends CANCELED
    PlanStatus.INVALID_REQUEST: E.INVALID_REQUEST,
}


def error_code(error: MaruError) -> int:
    """The code of a request refused before planning: INVALID_PLANNER, else the code of its status."""
    return E.INVALID_PLANNER if isinstance(error, InvalidPlanner) else STATUS_TO_ERROR[status_of(error)]


def yaw_from_quaternion(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def set_yaw(q, yaw: float) -> None:
    q.x, q.y, q.z, q.w = 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def grid_from_msg(msg: OccupancyGridMsg, *, occupied_threshold: int = 65, unknown_is_occupied: bool = True):
    """nav_msgs/OccupancyGrid -> OccupancyGrid; InvalidMap (or TooLarge) naming what is wrong."""
    info = msg.info
    if not (math.isfinite(info.resolution) and info.resolution > 0):
        raise InvalidMap(f"map resolution must be > 0, got {info.resolution}")
    p = info.origin.position
    origin = (p.x, p.y, yaw_from_quaternion(info.origin.orientation))
    if not all(math.isfinite(v) for v in origin):
        raise InvalidMap(f"map origin is not finite: {origin}")
    # resolution is a float32 in the message: recover the decimal map_server wrote (0.1, not 0.100000001)
    resolution = float(f"{info.resolution:.7g}")
    return OccupancyGrid.from_values(
        np.asarray(msg.data, dtype=np.int8),
        info.width,
        info.height,
        resolution,
        origin,
        occupied_threshold=occupied_threshold,
        unknown_is_occupied=unknown_is_occupied,
        frame_id=msg.header.frame_id or "map",
    )


def grid_to_msg(grid: OccupancyGrid, occupied: np.ndarray, stamp, frame_id: str) -> OccupancyGridMsg:
    """A grown map as nav_msgs/OccupancyGrid (100 grown/occupied, 0 free)."""
    return _values_msg(grid, np.where(np.asarray(occupied, dtype=bool), 100, 0).astype(np.int8), stamp, frame_id)


def costmap_to_msg(grid: OccupancyGrid, layer: CostLayer, stamp, frame_id: str) -> OccupancyGridMsg:
    """A cost layer as nav_msgs/OccupancyGrid, scaled as Nav2's costmap publisher (0 free .. 99 inscribed,
    100 lethal, -1 unknown)."""
    return _values_msg(grid, to_occupancy_values(layer.cost, grid.unknown), stamp, frame_id)


def _values_msg(grid: OccupancyGrid, values: np.ndarray, stamp, frame_id: str) -> OccupancyGridMsg:
    msg = OccupancyGridMsg()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.info.resolution = float(grid.resolution)
    msg.info.width, msg.info.height = grid.width, grid.height
    msg.info.origin.position.x, msg.info.origin.position.y = grid.origin[0], grid.origin[1]
    set_yaw(msg.info.origin.orientation, grid.origin[2])
    msg.data = np.asarray(values, dtype=np.int8).ravel().tolist()
    return msg


def pose_from_msg(pose: PoseStamped) -> tuple[float, float, float]:
    p, q = pose.pose.position, pose.pose.orientation
    if not all(math.isfinite(v) for v in (q.x, q.y, q.z, q.w)):
        return (p.x, p.y, math.nan)
    return (p.x, p.y, yaw_from_quaternion(q))


def path_to_msg(path: np.ndarray, stamp, frame_id: str) -> Path:
    msg = Path()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    for x, y, theta in np.asarray(path).reshape(-1, 3):
        pose = PoseStamped()
        pose.header = msg.header
        pose.pose.position.x, pose.pose.position.y = float(x), float(y)
        set_yaw(pose.pose.orientation, float(theta))
        msg.poses.append(pose)
    return msg


def footprint_from_points(points: list[Point32]) -> np.ndarray:
    return np.array([[p.x, p.y] for p in points], dtype=float).reshape(-1, 2)


def footprint_from_param(values) -> np.ndarray:
    values = [float(v) for v in values]
    if len(values) % 2:
        raise InvalidRequest(f"footprint parameter needs x, y pairs, got {len(values)} numbers")
    return np.array(values).reshape(-1, 2)


def stats_json(stats: PlanStats) -> str:
    return json.dumps(stats.to_dict())
