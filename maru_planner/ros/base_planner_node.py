"""base_planner_node: mobile-base grid planning (paper 002's MSPP and friends) on /map.

- subscribes ``map`` (nav_msgs/OccupancyGrid, transient local, reliable: a
  map_server latches it);
- serves ``plan_base_path`` (maru_planner_interfaces/PlanBasePath: planner
  id, footprint, start, goal -> Path, Nav2-style error code + message, stats)
  and ``make_plan`` (nav_msgs/GetPlan, the standard service: empty path on
  failure, the reason in the log);
- publishes the last path on ``plan`` (nav_msgs/Path) and, only while someone
  subscribes, the grown maps on ``~/eca_map``, ``~/baa_map`` and
  ``~/grown_map`` (nav_msgs/OccupancyGrid).

Parameters (``config/base_planner.yaml``): ``planner_id``, ``footprint``
(flat x, y list in base_link), ``headings``, ``allowed_planning_time``,
``unknown_is_occupied``, ``occupied_threshold``, ``map_topic``, ``biped_world``
(3-D world YAML for ``biped_track`` / ``biped_wall``; empty = plan on /map).
Poses are in the map frame (an empty frame_id is taken as the map's).
"""

from __future__ import annotations

import inspect
import math

import rclpy
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from maru_planner.base import registry
from maru_planner.errors import InvalidPlanner, MaruError
from maru_planner.ros import base_conversions as conv
from maru_planner.ros.env import network_from_environment
from maru_planner_interfaces.srv import PlanBasePath

E = PlanBasePath.Response

NODE_PARAMETERS = {
    "planner_id": "mspp",
    "footprint": [0.45, 0.15, -0.45, 0.15, -0.45, -0.15, 0.45, -0.15],
    "headings": 32,
    "allowed_planning_time": 10.0,
    "unknown_is_occupied": True,
    "occupied_threshold": 65,
    "map_topic": "map",
    "biped_world": "",
}


class BasePlannerNode(Node):
    def __init__(self):
        super().__init__("base_planner_node")
        for name, default in NODE_PARAMETERS.items():
            self.declare_parameter(name, default)
        self.grid = None
        self.map_error = "no map received yet on " + self._param("map_topic")
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self.create_subscription(OccupancyGridMsg, self._param("map_topic"), self._on_map, latched)
        self.path_pub = self.create_publisher(Path, "plan", latched)
        self.layer_pubs = {
            name: self.create_publisher(OccupancyGridMsg, f"~/{name}_map", latched) for name in ("eca", "baa", "grown")
        }
        self.create_service(PlanBasePath, "plan_base_path", self._on_plan_base_path)
        self.create_service(GetPlan, "make_plan", self._on_get_plan)
        self.requests = 0
        self.get_logger().info(
            f"base planner ready (default planner {self._param('planner_id')!r}, planners {registry.planner_ids()})"
        )

    def _param(self, name):
        return self.get_parameter(name).value

    # -------------------------------------------------------------------- map
    def _on_map(self, msg: OccupancyGridMsg):
        try:
            self.grid = conv.grid_from_msg(
                msg,
                occupied_threshold=int(self._param("occupied_threshold")),
                unknown_is_occupied=bool(self._param("unknown_is_occupied")),
            )
            self.map_error = ""
            self.get_logger().info(f"map {self.grid.width} x {self.grid.height} cells of {self.grid.resolution} m")
        except ValueError as exc:
            self.grid = None
            self.map_error = f"the last map was rejected: {exc}"
            self.get_logger().warning(self.map_error)

    # --------------------------------------------------------------- planning
    def plan(self, planner_id: str, footprint, start_msg, goal_msg, time_limit: float):
        """Returns (error_code, message, result or None, nav_msgs/Path of the result or None)."""
        self.requests += 1
        if self.grid is None:
            return E.NO_MAP, f"no map: {self.map_error}", None, None
        for name, pose in (("start", start_msg), ("goal", goal_msg)):
            frame = pose.header.frame_id
            if frame and frame != self.grid.frame_id:
                return (
                    E.INVALID_REQUEST,
                    (f"{name} is in frame {frame!r}; poses must be in the map frame {self.grid.frame_id!r}"),
                    None,
                    None,
                )
        if not (math.isfinite(time_limit) and time_limit >= 0):
            return E.INVALID_REQUEST, f"allowed_planning_time must be >= 0 s, got {time_limit}", None, None
        planner_id = planner_id or self._param("planner_id")
        if len(footprint) == 0:
            footprint = conv.footprint_from_param(self._param("footprint"))
        params = {
            "headings": int(self._param("headings")),
            "time_limit": time_limit or float(self._param("allowed_planning_time")),
        }
        if planner_id.startswith("biped_") and self._param("biped_world"):
            params["world"] = str(self._param("biped_world"))
        try:
            if planner_id not in registry.PLANNERS:
                raise InvalidPlanner(f"unknown base planner {planner_id!r}; known: {', '.join(registry.planner_ids())}")
            params = _accepted(registry.PLANNERS[planner_id], params)
            result = registry.plan(
                planner_id, self.grid, conv.pose_from_msg(start_msg), conv.pose_from_msg(goal_msg), footprint, **params
            )
        except InvalidPlanner as exc:
            return E.INVALID_PLANNER, str(exc), None, None
        except MaruError as exc:
            return E.INVALID_REQUEST, str(exc), None, None
        except Exception as exc:  # keep serving; say what broke
            self.get_logger().error(f"planner {planner_id!r} raised {type(exc).__name__}: {exc}")
            return E.UNKNOWN, f"planner {planner_id!r} failed: {type(exc).__name__}: {exc}", None, None
        path_msg = self._publish(result)
        return conv.STATUS_TO_ERROR[result.status], result.message, result, path_msg

    def _publish(self, result) -> Path:
        """Publish the path (when solved) and the watched layers; returns the path message for the response."""
        stamp = self.get_clock().now().to_msg()
        frame = self.grid.frame_id
        path_msg = conv.path_to_msg(result.path, stamp, frame)
        if result.success:
            self.path_pub.publish(path_msg)
        for name, pub in self.layer_pubs.items():
            layer = result.layers.get(name)
            if layer is not None and pub.get_subscription_count() > 0:
                pub.publish(conv.grid_to_msg(self.grid, layer, stamp, frame))
        return path_msg

    def _on_plan_base_path(self, request, response):
        code, message, result, path_msg = self.plan(
            request.planner_id,
            conv.footprint_from_points(request.footprint),
            request.start,
            request.goal,
            request.allowed_planning_time,
        )
        response.error_code, response.error_msg = code, message
        response.path.header.frame_id = self.grid.frame_id if self.grid is not None else "map"
        if result is not None:
            response.path = path_msg
            stats = result.stats
            response.deciding_stage = str(stats.get("deciding_stage", ""))
            response.planning_time = float(stats.get("planning_time", 0.0))
            response.expansions = int(stats.get("expansions", 0))
            response.collision_checks = int(stats.get("collision_checks", 0))
            response.stats_json = conv.stats_json(stats)
        self._log_outcome("plan_base_path", code, message)
        return response

    def _on_get_plan(self, request, response):
        code, message, result, path_msg = self.plan("", [], request.start, request.goal, 0.0)
        if result is not None and result.success:
            response.plan = path_msg
        else:
            response.plan.header.frame_id = self.grid.frame_id if self.grid is not None else "map"
        self._log_outcome("make_plan", code, message)
        return response

    def _log_outcome(self, service, code, message):
        if code == E.NONE:
            self.get_logger().info(f"{service}: {message}")
        else:
            self.get_logger().warning(f"{service}: error {code}: {message}")


def _accepted(factory, params: dict) -> dict:
    """Only the node-level parameters a planner factory takes (all of them for **kwargs factories)."""
    signature = inspect.signature(factory)
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in signature.parameters.values()):
        return params
    return {k: v for k, v in params.items() if k in signature.parameters}


def main(args=None):
    network = network_from_environment()
    rclpy.init(args=args)
    node = BasePlannerNode()
    node.get_logger().info(network)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.get_logger().info(f"served {node.requests} requests")
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()


if __name__ == "__main__":
    main()
