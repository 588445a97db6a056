"""reactive_node: the modified elastic strip (paper 001) driven by /scan.

Subscribes ``scan`` (LaserScan), ``odom`` (Odometry), ``plan`` (Path, the
initial path) and ``goal_pose`` (PoseStamped). Every valid scan gives exactly
one update: a ``cmd_vel`` Twist, the strip on ``~/strip`` (nav_msgs/Path),
arm joint commands on ``~/arm_command`` (JointTrajectory) and, when someone
listens, markers on ``~/markers``. ``~/cmd_vel_stamped`` (TwistStamped) repeats
every command stamped with the time of the scan it answers. Names are relative: ``/scan`` etc. in the
root namespace, ``/robot1/scan`` with ``-r __ns:=/robot1``.

Each scan is paired with the odometry of its time: it waits (at most until
the next scan arrives) for an odometry message stamped at or after it.

Malformed scans are dropped with a throttled warning; a scan older than
``stale_scan_timeout`` stops the base (zero Twist). With
``use_message_stamps`` (default) every time the node uses comes from message
stamps, so replaying the same bag gives the same commands; otherwise the node
clock is used and a watchdog also stops the base when scans stop arriving.

Parameters: ``config/reactive.yaml``; the elastic-strip ones are the fields of
:class:`maru_planner.reactive.StripParams` and are declared from it.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
import traceback
from collections import deque

import numpy as np
import rclpy
import yaml
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from maru_planner.errors import MaruError
from maru_planner.reactive import ElasticStripController, ScanError, StripParams
from maru_planner.reactive.description import arm_joint_names
from maru_planner.ros import reactive_conversions as conv
from maru_planner.ros.env import configure_loopback_dds

NODE_PARAMETERS = {
    "use_message_stamps": True,
    "stale_scan_timeout": 0.5,
    "odom_sync": True,
    "odom_frame": "odom",
    "base_frame": "base_link",
    "scan_reliability": "best_effort",
    "publish_arm": True,
    "warn_throttle_period": 2.0,
    "goal_path_tolerance": 0.25,
    "status_period": 30.0,
}


class ThrottledWarnings:
    """Warn at most once per period per key, saying how many were suppressed meanwhile."""

    def __init__(self, logger, period_s: float):
        self._logger, self._period = logger, float(period_s)
        self._last: dict[str, float] = {}
        self._suppressed: dict[str, int] = {}

    def warn(self, key: str, message: str) -> None:
        now = time.monotonic()
        if now - self._last.get(key, -math.inf) < self._period:
            self._suppressed[key] = self._suppressed.get(key, 0) + 1
            return
        skipped = self._suppressed.pop(key, 0)
        suffix = f" ({skipped} more since last warning)" if skipped else ""
        self._last[key] = now
        self._logger.warning(message + suffix)


def _strip_param_defaults() -> dict[str, object]:
    """ROS-parameter defaults for every StripParams field (tuples become lists)."""
    defaults = {}
    for f in dataclasses.fields(StripParams):
        value = f.default if f.default is not dataclasses.MISSING else f.default_factory()  # type: ignore[misc]
        defaults[f.name] = list(value) if isinstance(value, tuple) else value
    return defaults


def strip_params_from_config(path) -> StripParams:
    """StripParams from a ``--params-file`` YAML (section ``/**/reactive_node``), defaults elsewhere.

    Lets tools outside ROS (the bag recorder, benchmarks) run the controller
    exactly as the node configured from the same file would.
    """
    with open(path) as stream:
        params = node_section(yaml.safe_load(stream) or {})
    return StripParams.from_dict({k: v for k, v in params.items() if k not in NODE_PARAMETERS})


def node_section(params_file: dict) -> dict:
    """The ``ros__parameters`` of reactive_node in a parsed params file (``reactive_node`` or ``/**/reactive_node``)."""
    for key in ("/**/reactive_node", "reactive_node", "/reactive_node", "/**"):
        if key in params_file:
            return params_file[key].get("ros__parameters", {})
    return {}


class ReactiveNode(Node):
    """Convert messages, call the elastic-strip controller, publish its commands."""

    def __init__(self, **kwargs):
        super().__init__("reactive_node", **kwargs)
        self._strip_defaults = _strip_param_defaults()
        for name, default in {**self._strip_defaults, **NODE_PARAMETERS}.items():
            if default is None:  # optional StripParams fields (e.g. a beam window): any type, unset = None
                self.declare_parameter(name, None, ParameterDescriptor(dynamic_typing=True))
            else:
                self.declare_parameter(name, default)
        self.params = self._read_strip_params()
        self.controller = ElasticStripController(self.params)
        self.warnings = ThrottledWarnings(self.get_logger(), self._param("warn_throttle_period"))
        self.use_stamps = bool(self._param("use_message_stamps"))
        self.stale_timeout = float(self._param("stale_scan_timeout"))
        if not math.isfinite(self.stale_timeout) or self.stale_timeout <= 0.0:
            raise ValueError(f"stale_scan_timeout must be a positive number of seconds, got {self.stale_timeout}")
        self.odom_frame = str(self._param("odom_frame"))
        self.base_frame = str(self._param("base_frame"))

        self.pose: conv.Pose2D | None = None
        self.odom_stamp: float | None = None
        self.pending = None  # (LaserScanData, header stamp) waiting for its odometry
        self.odom_sync = bool(self._param("odom_sync"))
        self.newest_stamp = -math.inf  # newest message stamp seen (seconds), the clock in stamp mode
        self.path: np.ndarray | None = None
        self.last_arm_stamp: float | None = None
        self.last_scan_received = time.monotonic()
        self.base_stopped = True
        self.counts = {"scans": 0, "updates": 0, "dropped": 0, "stale": 0}
        self.update_ms: deque[float] = deque(maxlen=200)  # recent controller update times, for the status line
        self._goal_logged = False

        self._setup_arm()
        self._setup_topics()

    # ------------------------------------------------------------ set-up
    def _param(self, name: str):
        return self.get_parameter(name).value

    def _read_strip_params(self) -> StripParams:
        try:
            values = {name: self._param(name) for name in self._strip_defaults}
            return StripParams.from_dict({k: tuple(v) if isinstance(v, list) else v for k, v in values.items()})
        except (TypeError, ValueError) as exc:
            raise ValueError(f"invalid reactive_node parameters: {exc}") from exc

    def _setup_arm(self) -> None:
        self.arm_names: list[str] = []
        if self._param("publish_arm"):
            self.arm_names = arm_joint_names("left") + arm_joint_names("right")

    def _setup_topics(self) -> None:
        reliability = str(self._param("scan_reliability"))
        if reliability not in ("best_effort", "reliable"):
            raise ValueError(f"scan_reliability must be 'best_effort' or 'reliable', not {reliability!r}")
        scan_qos = QoSProfile(
            depth=5,
            reliability=ReliabilityPolicy.RELIABLE if reliability == "reliable" else ReliabilityPolicy.BEST_EFFORT,
        )
        # Creation order matters: when several messages are ready at once the executor takes them in
        # this order, so a goal or plan that arrived with a scan is applied before that scan.
        self.odom_topic = self.create_subscription(Odometry, "odom", self.on_odom, 10).topic_name
        self.create_subscription(PoseStamped, "goal_pose", self.on_goal, 10)
        self.create_subscription(Path, "plan", self.on_plan, 10)
        self.scan_topic = self.create_subscription(LaserScan, "scan", self.on_scan, scan_qos).topic_name
        self.cmd_pub = self.create_publisher(Twist, "cmd_vel", 10)
        self.cmd_stamped_pub = self.create_publisher(TwistStamped, "~/cmd_vel_stamped", 10)
        self.strip_pub = self.create_publisher(Path, "~/strip", 10)
        self.arm_pub = self.create_publisher(JointTrajectory, "~/arm_command", 10)
        self.marker_pub = self.create_publisher(MarkerArray, "~/markers", 10)
        if not self.use_stamps:
            self.create_timer(max(self.stale_timeout / 2.0, 0.01), self.on_watchdog)
        if float(self._param("status_period")) > 0.0:
            self.create_timer(float(self._param("status_period")), self.log_status)

    def log_status(self) -> None:
        self.get_logger().info(self.status())

    def status(self) -> str:
        text = "scans {scans}, updates {updates}, dropped {dropped}, stale {stale}".format(**self.counts)
        if self.update_ms:
            ms = np.array(self.update_ms)
            text += f"; update median {np.median(ms):.2f} ms, max {ms.max():.2f} ms (last {len(ms)})"
        return text

    # ------------------------------------------------------------ inputs
    def _now(self) -> float:
        if self.use_stamps:
            return self.newest_stamp
        return self.get_clock().now().nanoseconds / conv.NS_PER_S

    def _see_stamp(self, stamp) -> None:
        self.newest_stamp = max(self.newest_stamp, conv.stamp_to_s(stamp))

    def on_odom(self, msg: Odometry) -> None:
        if self.pose is None:
            self.get_logger().info(f"receiving odometry on {self.odom_topic}")
        stamp = conv.stamp_to_s(msg.header.stamp)
        if self.use_stamps and self.odom_stamp is not None and stamp < self.odom_stamp - self.stale_timeout:
            # e.g. `ros2 bag play --loop` starting over: restart the message clock instead of calling
            # every later scan stale
            jump = self.odom_stamp - stamp
            self.get_logger().warning(f"odometry time jumped back {jump:.2f} s: restarting the clock")
            self.newest_stamp = -math.inf
            self.pending = None
        self.pose = conv.pose_from_odom(msg)
        self.odom_stamp = stamp
        self._see_stamp(msg.header.stamp)
        self._process_pending(force=False)

    def on_goal(self, msg: PoseStamped) -> None:
        """A new goal; a /plan already received that ends there stays the initial path, else a straight line."""
        goal = conv.pose_from_pose_stamped(msg)
        tolerance = float(self._param("goal_path_tolerance"))
        if self.path is not None and np.hypot(*(self.path[-1, :2] - np.asarray(goal[:2]))) <= tolerance:
            self.controller.set_path(self.path)
        else:
            self.path = None
            self.controller.set_goal(goal)
        self._goal_logged = False
        self.get_logger().info(f"goal ({goal[0]:.2f}, {goal[1]:.2f}, {goal[2]:.2f})")

    def on_plan(self, msg: Path) -> None:
        """The initial path; its last pose becomes the goal (eq. 36-44 deform it from here on)."""
        points = conv.path_points_from_msg(msg)
        if len(points) < 2 or not np.all(np.isfinite(points)):
            self.warnings.warn("plan", f"ignored /plan with {len(points)} poses (need >= 2 finite poses)")
            return
        self.path = points
        self.controller.set_path(points)
        self._goal_logged = False
        self.get_logger().info(f"initial path with {len(points)} poses to ({points[-1, 0]:.2f}, {points[-1, 1]:.2f})")

    # ------------------------------------------------------------ the update
    def on_scan(self, msg: LaserScan) -> None:
        """Validate, then wait (at most until the next scan) for the odometry of the scan's time."""
        self.counts["scans"] += 1
        try:
            stamp = conv.stamp_to_s(msg.header.stamp) if self.use_stamps else self._now()
            scan = conv.scan_from_msg(msg, stamp=stamp)
        except ScanError as exc:
            self.counts["dropped"] += 1
            self.warnings.warn("malformed", f"dropped malformed scan: {exc}")
            return
        if self.use_stamps:
            self._see_stamp(msg.header.stamp)
        if self.counts["scans"] - self.counts["dropped"] == 1:
            self.get_logger().info(f"receiving scans on {self.scan_topic}")
        self.last_scan_received = time.monotonic()
        self._process_pending(force=True)
        self.pending = (scan, conv.stamp_to_s(msg.header.stamp))
        self._process_pending(force=not self.odom_sync)

    def _process_pending(self, force: bool) -> None:
        """Run the update for the waiting scan once odometry stamped at or after it is in (or when forced).

        Pairing each scan with the odometry of its own time, whatever order the two
        arrive in, is what makes a replayed bag give the same commands every time.
        """
        if self.pending is None:
            return
        scan, header_stamp = self.pending
        if not force and (self.odom_stamp is None or self.odom_stamp < header_stamp):
            return
        self.pending = None
        if self.odom_stamp is not None and self.odom_stamp < header_stamp - self.stale_timeout:
            lag = header_stamp - self.odom_stamp
            self.warnings.warn("odom", f"odometry is {lag:.3f} s older than the scan: using it anyway")
        scan_age = self._now() - header_stamp
        if scan_age > self.stale_timeout:
            self.counts["stale"] += 1
            self.warnings.warn("stale", f"scan is {scan_age:.3f} s old (> {self.stale_timeout} s): stopping the base")
            self._stop_base(header_stamp)
            return
        if self.pose is None or not self.controller.has_goal:
            missing = "odometry" if self.pose is None else "a goal"
            self.warnings.warn("waiting", f"no {missing} yet: holding still")
            self._stop_base(header_stamp)
            return
        try:
            self._update(scan, scan.stamp, header_stamp)
        except (MaruError, ValueError, RuntimeError) as exc:
            self.warnings.warn("update", f"update failed, stopping the base: {exc}")
            self._stop_base(header_stamp)
        except Exception:  # noqa: BLE001 - a controller bug must stop the base, not kill the node
            self.get_logger().error("controller update raised; stopping the base\n" + traceback.format_exc())
            self._stop_base(header_stamp)

    def _update(self, scan, stamp: float, header_stamp: float) -> None:
        out = self.controller.update(pose=self.pose, scan=scan)
        self.counts["updates"] += 1
        self.update_ms.append(out.update_time * 1e3)
        self._send_command(out.v, out.w, header_stamp)
        self.strip_pub.publish(conv.path_msg(np.asarray(out.strip), self.odom_frame, stamp))
        self._publish_arm(out, stamp)
        if self.marker_pub.get_subscription_count() > 0:
            self.marker_pub.publish(
                conv.strip_markers(out.strip, out.obstacle_points, out.target, self.odom_frame, stamp)
            )
        if out.reached_goal and not self._goal_logged:
            self.get_logger().info("goal reached")
            self._goal_logged = True

    def _publish_arm(self, out, stamp: float) -> None:
        if not self.arm_names or out.arm_joint_steps is None or out.arm_joint_positions is None:
            return
        # the scan period, for the velocities; a nominal one at start or after a time jump
        delta = stamp - self.last_arm_stamp if self.last_arm_stamp is not None else 0.0
        period = delta if 0.0 < delta <= 1.0 else 0.1
        self.last_arm_stamp = stamp
        self.arm_pub.publish(
            conv.arm_trajectory_msg(self.arm_names, out.arm_joint_positions, out.arm_joint_steps, period, stamp)
        )

    def _send_command(self, v: float, w: float, stamp: float) -> None:
        """cmd_vel, and the same command stamped with the time of the scan it answers."""
        self.cmd_pub.publish(conv.twist_msg(v, w))
        self.cmd_stamped_pub.publish(conv.twist_stamped_msg(v, w, self.base_frame, stamp))
        self.base_stopped = v == 0.0 and w == 0.0

    def _stop_base(self, stamp: float | None = None) -> None:
        self._send_command(0.0, 0.0, self._now() if stamp is None else stamp)

    def on_watchdog(self) -> None:
        """Clock mode only: stop the base once when scans stop arriving."""
        silent = time.monotonic() - self.last_scan_received
        if not self.base_stopped and silent > self.stale_timeout:
            self.warnings.warn("silent", f"no scan for {silent:.2f} s: stopping the base")
            self._stop_base()


def main(args=None) -> int:
    configure_loopback_dds()
    rclpy.init(args=args)
    try:
        node = ReactiveNode()
    except (ValueError, ParameterException) as exc:
        print(f"reactive_node: bad parameters: {exc}", file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.get_logger().info(node.status())
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
