"""The browser views of the nodes: ``planning_node``'s ``view`` option, and the base side live (``base_view``).

- :class:`PlanViewBridge`: a :class:`~maru_planner.web.plan_view.PlanView` on its own viser server (``view_host``,
  ``view_port``; the node logs its URL). A timer (``VIEW_PERIOD``, ~10 Hz) redraws the scene when the runtime's
  scene version changed and shows the latest ``/joint_states`` when they changed (held while a plan plays, so the
  plan is seen to its end); the node hands every plan it serves to :meth:`PlanViewBridge.show_result` (a failure
  shows its one-line message).
- :class:`BaseViewNode` (``python -m maru_planner.ros.plan_view_bridge``): ``reactive_node``'s run live -- ``odom``,
  ``scan`` (placed by ``laser_pose``), ``plan`` and the elastic strip (``strip_topic``) -- on a
  :class:`~maru_planner.web.base_live.LiveBaseView` over BARN world ``barn`` or the grid ``map_yaml``; each topic
  redrawn at most every ``VIEW_PERIOD``.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from nav_msgs.msg import Odometry
from nav_msgs.msg import Path as PathMsg
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

from maru_planner import errors
from maru_planner.base.grid import OccupancyGrid
from maru_planner.params import dataclass_params, param
from maru_planner.physics import barn_world
from maru_planner.planning.types import MotionResult
from maru_planner.reactive.controller import StripParams
from maru_planner.reactive.scan import ScanError, scan_to_points
from maru_planner.ros import parameters
from maru_planner.ros.lifecycle import run_node
from maru_planner.ros.reactive_conversions import pose_from_odom, scan_from_msg
from maru_planner.runtime import PlanningRuntime
from maru_planner.web.base_live import LiveBaseView
from maru_planner.web.plan_view import PlanView
from maru_planner.web.serving import DEFAULT_HOST, serve

VIEW_PERIOD = 0.1  # s: how often the scene version and the joint states are looked at; the base topics' redraws
BASE_VIEW_NODE = "base_view"


class ViewSettings(Protocol):
    """The node settings the view reads (``planning_parameters.NodeSettings``)."""

    view: bool
    view_host: str
    view_port: int


class PlanViewBridge:
    """The node's view (module doc); :meth:`close` stops its server (the timer goes with the node's cleanup)."""

    def __init__(self, node: Node, runtime: PlanningRuntime, host: str, port: int):
        self.view = PlanView.serve(runtime.source, runtime.robot, host, port)
        self._runtime = runtime
        self._scene_version = -1
        self._shown_state: dict[str, float] = {}
        self.refresh()
        self._timer = node.create_timer(VIEW_PERIOD, self.refresh, callback_group=MutuallyExclusiveCallbackGroup())
        node.get_logger().info(f"view: the live scene, start and plans at {self.view.url}")

    @property
    def url(self) -> str:
        return self.view.url

    def refresh(self) -> None:
        """Redraw a changed scene; show changed joint states unless a plan is playing."""
        if self._runtime.scene_version != self._scene_version:
            scene, self._scene_version = self._runtime.get_scene()
            self.view.show_scene(scene)
        state = self._runtime.latest_joint_state()
        if state and state != self._shown_state and not self.view.playing:
            self.view.show_start(state)
            self._shown_state = state

    def show_result(self, result: MotionResult, start: dict[str, float] | None) -> None:
        """Show a served plan: its summary and, when it succeeded, its trajectory played from ``start``."""
        self.view.show_result(result, start)

    def close(self) -> None:
        self.view.close()


def open_view(node: Node, runtime: PlanningRuntime, settings: ViewSettings) -> PlanViewBridge | None:
    """The node's view when its ``view`` parameter is true (InvalidRequest for a host not of this machine)."""
    return PlanViewBridge(node, runtime, settings.view_host, settings.view_port) if settings.view else None


@dataclass
class BaseViewSettings:
    """``base_view``'s parameters."""

    view_host: str = param(DEFAULT_HOST, "address the view is served on", read_only=True)
    view_port: int = param(8080, "the view's port (the next free one if taken; 0: any)", lower=0, upper=65535,
                           read_only=True)  # fmt: skip
    barn: int = param(-1, "BARN world drawn under the base (-1: none)", lower=-1, upper=barn_world.WORLD_COUNT - 1,
                      read_only=True)  # fmt: skip
    map_yaml: str = param("", "occupancy grid map YAML drawn under the base (empty: none)", read_only=True)
    laser_pose: list[float] = param(
        default_factory=lambda: list(StripParams().laser_pose),
        description="laser in base_link: x (m), y (m), yaw (rad), as reactive_node's strip.laser_pose",
        read_only=True,
    )
    strip_topic: str = param("/reactive_node/strip", "the elastic strip (nav_msgs/Path)", read_only=True)


BASE_VIEW_PARAMS = dataclass_params(BaseViewSettings)


def path_points(msg: PathMsg) -> np.ndarray:
    """(k, 2) x, y of a nav_msgs/Path."""
    return np.array([[p.pose.position.x, p.pose.position.y] for p in msg.poses], dtype=float).reshape(-1, 2)


class BaseViewNode(Node):
    """``reactive_node``'s base run live in a browser (module doc); InvalidRequest for a bad world, map or host."""

    def __init__(self, **kwargs: Any):
        super().__init__(BASE_VIEW_NODE, **kwargs)
        self.settings = BaseViewSettings(**parameters.declare_parameters(self, BASE_VIEW_PARAMS))
        settings = self.settings
        if len(settings.laser_pose) != 3:
            raise errors.InvalidParameter(f"laser_pose must be [x, y, yaw], got {list(settings.laser_pose)}")
        barn = barn_world.world_grid(settings.barn) if settings.barn >= 0 else None
        try:
            grid = OccupancyGrid.from_yaml(settings.map_yaml) if settings.map_yaml else None
        except (OSError, ValueError) as exc:
            raise errors.InvalidRequest(f"map_yaml {settings.map_yaml}: {errors.one_line(exc, 160)}") from None
        self.view = LiveBaseView(serve(settings.view_host, settings.view_port), grid, barn)
        self._shown: dict[str, float] = {}
        self.create_subscription(Odometry, "odom", self._throttled("odom", self._on_odom), 10)
        self.create_subscription(LaserScan, "scan", self._throttled("scan", self._on_scan), qos_profile_sensor_data)
        self.create_subscription(PathMsg, "plan", lambda msg: self.view.show_path(path_points(msg)), 1)
        self.create_subscription(PathMsg, settings.strip_topic, self._throttled("strip", self._on_strip), 10)
        self.create_timer(1.0, self.view.refresh_summary)
        server = self.view.server
        self.url = f"http://{server.get_host()}:{server.get_port()}"
        self.get_logger().info(f"the base run live at {self.url}")

    def _throttled(self, topic: str, show: Callable[[Any], None]) -> Callable[[Any], None]:
        """``show`` for at most one message of ``topic`` per ``VIEW_PERIOD`` (a page needs no more)."""

        def callback(msg: Any) -> None:
            now = time.monotonic()
            if now - self._shown.get(topic, -1.0) >= VIEW_PERIOD:
                self._shown[topic] = now
                show(msg)

        return callback

    def _on_odom(self, msg: Odometry) -> None:
        try:
            x, y, yaw = pose_from_odom(msg)
        except (errors.MaruError, ValueError) as exc:
            self.get_logger().warning(f"ignoring odometry: {errors.one_line(exc)}", throttle_duration_sec=5.0)
            return
        self.view.show_pose(x, y, yaw)

    def _on_scan(self, msg: LaserScan) -> None:
        try:
            scan = scan_from_msg(msg)
        except ScanError as exc:
            self.get_logger().warning(f"ignoring a scan: {errors.one_line(exc)}", throttle_duration_sec=5.0)
            return
        self.view.show_scan(scan_to_points(scan, tuple(self.settings.laser_pose), max_range=scan.range_max),
                            in_base=True)  # fmt: skip

    def _on_strip(self, msg: PathMsg) -> None:
        self.view.show_strip(path_points(msg))

    def destroy_node(self) -> None:
        self.view.server.stop()
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """``python -m maru_planner.ros.plan_view_bridge [--ros-args -p barn:=N]``; exit code 2 on bad start-up input."""
    return run_node(BASE_VIEW_NODE, BaseViewNode, args, startup_errors=(errors.MaruError, OSError, ValueError))


if __name__ == "__main__":
    sys.exit(main())
