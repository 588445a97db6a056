"""reactive_node: the modified elastic strip (paper 001) driven by /scan.

Subscribes ``scan`` (LaserScan), ``odom`` (Odometry), ``plan`` (Path, the
initial path) and ``goal_pose`` (PoseStamped). Every valid scan gives exactly
one update: a ``cmd_vel`` Twist, the strip on ``~/strip`` (nav_msgs/Path),
arm joint commands on ``~/arm_command`` (JointTrajectory) and, when someone
listens, markers on ``~/markers``. ``~/cmd_vel_stamped`` (TwistStamped) repeats
every command stamped with the time of the scan it answers. Names are relative: ``/scan`` etc. in the
root namespace, ``/robot1/scan`` with ``-r __ns:=/robot1``.

Time is ROS time: the system clock, or ``/clock`` with ``use_sim_time`` (a bag
played with ``ros2 bag play --clock``, a simulator), so replaying a bag gives
the same commands every time. Each scan is paired with the odometry of its
time: it waits (at most until the next scan arrives) for an odometry message
stamped at or after it.

No message can stop the node: malformed scans, goals, plans and odometry are
dropped with a throttled warning and counted, scans or odometry stamped more
than ``future_tolerance`` ahead of the clock are dropped (never taken as
"now"), a scan older than ``stale_scan_timeout`` stops the base (zero Twist),
and a watchdog on the wall clock stops the base when no valid scan arrived
for ``scan_timeout`` seconds, in both clock modes.

Bounded work and memory per message: a /plan arrives serialized and its pose count is read first, so one
longer than ``max_plan_poses`` is refused (counted as ``oversized``) before rclpy builds a Python object per
pose (100,000 poses took 1.7 s), as is one larger than 512 bytes a pose (long frame ids); the input queues hold
one message each (the newest; best-effort scans, goals, plans), so the node is never more than one scan behind
and holds at most queue depth x message size.
An exception in a callback is logged on one line and stops the base; the node keeps serving.

A managed node (:mod:`maru_planner.ros.lifecycle`): configure reads the parameters and creates the
publishers; activate subscribes to the inputs and starts the watchdog, so the node commands the base
only while active; deactivate publishes a zero ``cmd_vel``, unsubscribes and forgets the goal and
path (a new goal is needed after the next activation).

Parameters: ``config/reactive.yaml``. Every field of :class:`StripParams` and
of :class:`NodeSettings` is declared with its description and range; what
changes at run time applies from the next scan, ``scan_reliability`` is
read-only.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np
import yaml
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path
from rclpy.clock import Clock, ClockType, JumpThreshold, TimeJump
from rclpy.duration import Duration
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rclpy.subscription import Subscription
from rclpy.timer import Timer
from sensor_msgs.msg import LaserScan
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from maru_planner.errors import InvalidRequest, MaruError, one_line
from maru_planner.params import dataclass_params, param
from maru_planner.reactive import ControlOutput, ElasticStripController, LaserScanData, ScanError, StripParams
from maru_planner.reactive.description import arm_joint_names
from maru_planner.ros import parameters
from maru_planner.ros import reactive_conversions as conv
from maru_planner.ros.lifecycle import ManagedNode, run_node


@dataclasses.dataclass(frozen=True)
class NodeSettings:
    """reactive_node's own parameters (the controller's are :class:`StripParams`)."""

    stale_scan_timeout: float = param(
        0.5, "s: a scan older than this on the node's clock stops the base", lower=0.01, upper=60.0
    )
    scan_timeout: float = param(
        0.5, "s of wall time without a valid scan before the watchdog stops the base", lower=0.05, upper=3600.0
    )
    future_tolerance: float = param(
        0.5, "s: a scan or odometry stamped further ahead of the node's clock is dropped", lower=0.0, upper=60.0
    )
    odom_sync: bool = param(True, "hold a scan until odometry stamped at or after it arrives (at most one scan)")
    odom_frame: str = param("odom", "frame of the strip and markers")
    base_frame: str = param("base_link", "frame of the stamped command")
    scan_reliability: str = param(
        "best_effort",
        "QoS of the scan subscription (reliable for lock-step replays)",
        choices=("best_effort", "reliable"),
        read_only=True,
    )
    publish_arm: bool = param(True, "publish ~/arm_command")
    warn_throttle_period: float = param(2.0, "s between repeats of one kind of warning", lower=0.0, upper=3600.0)
    goal_path_tolerance: float = param(
        0.25, "m: a /plan ending this close to a new /goal_pose stays the initial path", lower=0.0, upper=100.0
    )
    status_period: float = param(
        30.0, "s of wall time between status lines in the log (0 = off)", lower=0.0, upper=86400.0
    )
    max_plan_poses: int = param(
        5000,
        "a /plan with more poses is refused before it is decoded (counted as oversized): bounded work per message",
        lower=2,
        upper=100_000,
    )


# a serialized /plan larger than this is refused unread: a pose with a frame id of ~400 characters, the Path's header
PLAN_BYTES_PER_POSE, PLAN_BYTES_FIXED = 512, 1024
NODE_SPECS = dataclass_params(NodeSettings)
STRIP_SPECS = dataclass_params(StripParams)
SPECS = {**STRIP_SPECS, **NODE_SPECS}  # every parameter the node declares
ROS_PARAMETERS = ("use_sim_time",)  # declared by rclpy itself


class ThrottledWarnings:
    """Log at most once per period per key, saying how many were suppressed meanwhile."""

    def __init__(self, logger: Any, period_s: float, clock: Callable[[], float] = time.monotonic) -> None:
        self._logger, self.period, self._clock = logger, float(period_s), clock
        self._last: dict[str, float] = {}
        self._suppressed: dict[str, int] = {}

    def warn(self, key: str, message: str) -> None:
        self._emit(key, message, self._logger.warning)

    def error(self, key: str, message: str) -> None:
        self._emit(key, message, self._logger.error)

    def _emit(self, key: str, message: str, log: Callable[[str], Any]) -> None:
        now = self._clock()
        if now - self._last.get(key, -math.inf) < self.period:
            self._suppressed[key] = self._suppressed.get(key, 0) + 1
            return
        skipped = self._suppressed.pop(key, 0)
        suffix = f" ({skipped} more since last warning)" if skipped else ""
        self._last[key] = now
        log(message + suffix)


def strip_params_from_config(path: str | os.PathLike) -> StripParams:
    """StripParams from a ``--params-file`` YAML (section ``/**``, ``/**/reactive_node`` ...), defaults elsewhere.

    Lets tools outside ROS (the bag recorder, benchmarks) run the controller
    exactly as the node configured from the same file would.
    """
    with open(path) as stream:
        params = node_section(yaml.safe_load(stream) or {})
    node_only = set(NODE_SPECS) | set(ROS_PARAMETERS)
    return StripParams.from_dict({k: v for k, v in params.items() if k not in node_only})


def node_section(params_file: dict) -> dict:
    """The ``ros__parameters`` of reactive_node in a parsed params file (``/**``, ``reactive_node`` ...)."""
    for key in ("/**/reactive_node", "reactive_node", "/reactive_node", "/**"):
        if key in params_file:
            return params_file[key].get("ros__parameters", {})
    return {}


class ReactiveNode(ManagedNode):
    """Convert messages, call the elastic-strip controller, publish its commands."""

    def __init__(self, **kwargs: Any) -> None:
        """InvalidParameter (one line) for a bad parameter; with ``autostart`` what configuring raises."""
        super().__init__("reactive_node", **kwargs)
        values = parameters.declare_parameters(self, SPECS)
        self.settings = NodeSettings(**{name: values[name] for name in NODE_SPECS})
        self.warnings = ThrottledWarnings(self.get_logger(), self.settings.warn_throttle_period)

        self.pose: conv.Pose2D | None = None
        self.odom_stamp: float | None = None
        self.pending: LaserScanData | None = None  # the scan waiting for its odometry
        self.path: np.ndarray | None = None
        self.last_arm_stamp: float | None = None
        self.last_valid_scan = time.monotonic()
        self.base_stopped = True
        self.counts = dict.fromkeys(
            ("scans", "updates", "dropped", "stale", "future", "bad_goals", "bad_plans", "oversized", "bad_odometry",
             "errors"), 0,
        )  # fmt: skip
        self.update_ms: deque[float] = deque(maxlen=200)  # recent controller update times, for the status line
        self._goal_logged = False
        self._watchdog: Timer | None = None
        self._status_timer: Timer | None = None
        self._inputs: list[Subscription] = []
        parameters.add_on_set_parameters_callback(self, SPECS, self.when_configured(self.apply_parameters))
        self.start()

    # ------------------------------------------------------------ lifecycle
    def configure(self) -> None:
        """Read the parameters, build the controller, create the publishers, follow clock jumps."""
        values = parameters.read_parameters(self, SPECS)
        self.settings = NodeSettings(**{name: values[name] for name in NODE_SPECS})
        self.controller = ElasticStripController(StripParams(**{name: values[name] for name in STRIP_SPECS}))
        self.warnings.period = self.settings.warn_throttle_period
        self.arm_names = self._arm_names()
        self.cmd_pub = self.create_lifecycle_publisher(Twist, "cmd_vel", 10)
        self.cmd_stamped_pub = self.create_lifecycle_publisher(TwistStamped, "~/cmd_vel_stamped", 10)
        self.strip_pub = self.create_lifecycle_publisher(Path, "~/strip", 10)
        self.arm_pub = self.create_lifecycle_publisher(JointTrajectory, "~/arm_command", 10)
        self.marker_pub = self.create_lifecycle_publisher(MarkerArray, "~/markers", 10)
        self._jump_handle = self.get_clock().create_jump_callback(
            JumpThreshold(min_forward=None, min_backward=Duration(nanoseconds=-1), on_clock_change=False),
            post_callback=self.on_time_jump,
        )

    def activate(self) -> None:
        """Inputs from now on: fresh odometry and scans, the watchdog armed."""
        self.pose, self.odom_stamp, self.pending, self.last_arm_stamp = None, None, None, None
        self.last_valid_scan = time.monotonic()
        self.base_stopped = True
        self._subscribe_inputs()
        self._setup_timers()

    def deactivate(self) -> None:
        """A zero ``cmd_vel`` (the publishers still publish), then no inputs, no timers, no goal."""
        self._stop_base()
        for subscription in self._inputs:
            self.destroy_subscription(subscription)
        self._inputs = []
        self._destroy_timers()
        self.controller = ElasticStripController(self.controller.params)
        self.path = None

    def cleanup(self) -> None:
        self._jump_handle.unregister()

    # ------------------------------------------------------------ set-up
    def _arm_names(self) -> list[str]:
        return arm_joint_names("left") + arm_joint_names("right") if self.settings.publish_arm else []

    def _subscribe_inputs(self) -> None:
        reliable = self.settings.scan_reliability == "reliable"
        scan_qos = QoSProfile(  # reliable (lock-step replays) keeps a few; live scans only the newest
            depth=5 if reliable else 1,
            reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        )
        # Creation order matters: when several messages are ready at once the executor takes them in
        # this order, so a goal or plan that arrived with a scan is applied before that scan.
        self._inputs = [
            self.create_subscription(Odometry, "odom", self._guarded("odom", self.on_odom), 10),
            self.create_subscription(PoseStamped, "goal_pose", self._guarded("goal_pose", self.on_goal), 1),
            self.create_subscription(Path, "plan", self._guarded("plan", self.on_plan_bytes), 1, raw=True),
            self.create_subscription(LaserScan, "scan", self._guarded("scan", self.on_scan), scan_qos),
        ]
        self.odom_topic, self.scan_topic = self._inputs[0].topic_name, self._inputs[3].topic_name

    def _destroy_timers(self) -> None:
        for timer in (self._watchdog, self._status_timer):
            if timer is not None:
                self.destroy_timer(timer)
        self._watchdog = self._status_timer = None

    def _setup_timers(self) -> None:
        """The watchdog and the status line run on the wall clock, whatever clock the node uses."""
        self._destroy_timers()
        wall = Clock(clock_type=ClockType.STEADY_TIME)
        period = max(self.settings.scan_timeout / 4.0, 0.01)
        self._watchdog = self.create_timer(period, self._guarded("watchdog", self.on_watchdog), clock=wall)
        if self.settings.status_period > 0.0:
            self._status_timer = self.create_timer(self.settings.status_period, self.log_status, clock=wall)

    def apply_parameters(self, changes: dict[str, Any]) -> None:
        """A run-time parameter change: checked as a whole, then applied from the next scan on.

        InvalidRequest (the reason the caller sees) when the new values do not fit together.
        """
        strip_changes = {k: v for k, v in changes.items() if k in STRIP_SPECS}
        node_changes = {k: v for k, v in changes.items() if k in NODE_SPECS}
        strip_params = dataclasses.replace(self.controller.params, **strip_changes) if strip_changes else None
        previous, self.settings = self.settings, dataclasses.replace(self.settings, **node_changes)
        if strip_params is not None:
            self.controller.set_params(strip_params)
        self.warnings.period = self.settings.warn_throttle_period
        self.arm_names = self._arm_names()
        timing = (self.settings.scan_timeout, self.settings.status_period)
        if self.is_active and (previous.scan_timeout, previous.status_period) != timing:
            self._setup_timers()
        self.get_logger().info("parameters set: " + ", ".join(f"{k}={v!r}" for k, v in changes.items()))

    def _guarded(self, name: str, callback: Callable[..., None]) -> Callable[..., None]:
        """``callback`` with an error boundary: an exception is counted, logged on one line and stops the base."""

        def guarded(*args) -> None:
            try:
                callback(*args)
            except Exception as exc:  # noqa: BLE001 - no message may kill the node; it keeps serving
                self.counts["errors"] += 1
                self.warnings.error(
                    f"error:{name}", f"{name} callback failed, stopping the base: {type(exc).__name__}: {one_line(exc)}"
                )
                self._stop_base()

        return guarded

    def log_status(self) -> None:
        self.get_logger().info(self.status())

    def status(self) -> str:
        c = self.counts
        parts = ["scans {scans}, updates {updates}, dropped {dropped}, stale {stale}".format(**c)]
        if self.update_ms:
            ms = np.array(self.update_ms)
            parts.append(f"update median {np.median(ms):.2f} ms, max {ms.max():.2f} ms (last {len(ms)})")
        parts.append(
            "future {future}, rejected goals {bad_goals}, plans {bad_plans}, oversized {oversized}, "
            "odometry {bad_odometry}, "
            "callback errors {errors}".format(**c)
        )
        return "; ".join(parts)

    # ------------------------------------------------------------ time
    def _now(self) -> float:
        return self.get_clock().now().nanoseconds / conv.NS_PER_S

    def _in_time(self, stamp: float, what: str) -> bool:
        """False (counted, warned) for a message stamped more than future_tolerance ahead of the clock."""
        now = self._now()
        ahead = stamp - now
        if ahead <= self.settings.future_tolerance:
            return True
        self.counts["future"] += 1
        hint = " (no /clock received yet?)" if now == 0.0 else ""
        self.warnings.warn(
            f"future:{what}",
            f"dropped {what} stamped {ahead:.3f} s ahead of the clock "
            f"(future_tolerance {self.settings.future_tolerance} s){hint}",
        )
        return False

    def on_time_jump(self, jump: TimeJump) -> None:
        """The clock went back (``ros2 bag play --loop`` starting over, a simulator reset): drop the held scan."""
        self.pending = None
        self.last_arm_stamp = None
        self.get_logger().warning(f"time jumped back {-jump.delta.nanoseconds / conv.NS_PER_S:.2f} s")

    # ------------------------------------------------------------ inputs
    def on_odom(self, msg: Odometry) -> None:
        try:
            pose = conv.pose_from_odom(msg)
        except InvalidRequest as exc:
            self.counts["bad_odometry"] += 1
            self.warnings.warn("odom_input", f"dropped odometry: {exc}")
            return
        stamp = conv.stamp_to_s(msg.header.stamp)
        if not self._in_time(stamp, "odometry"):
            return
        if self.pose is None:
            self.get_logger().info(f"receiving odometry on {self.odom_topic}")
        self.pose, self.odom_stamp = pose, stamp
        self._process_pending(force=False)

    def on_goal(self, msg: PoseStamped) -> None:
        """A new goal; a /plan already received that ends there stays the initial path, else a straight line."""
        try:
            goal = conv.pose_from_pose_stamped(msg)
        except InvalidRequest as exc:
            self.counts["bad_goals"] += 1
            self.warnings.warn("goal", f"ignored /goal_pose: {exc}")
            return
        tolerance = self.settings.goal_path_tolerance
        if self.path is not None and np.hypot(*(self.path[-1, :2] - np.asarray(goal[:2]))) <= tolerance:
            self.controller.set_path(self.path)
        else:
            self.path = None
            self.controller.set_goal(goal)
        self._goal_logged = False
        self.get_logger().info(f"goal ({goal[0]:.2f}, {goal[1]:.2f}, {goal[2]:.2f})")

    def on_plan_bytes(self, raw: bytes) -> None:
        """A serialized /plan: refused unread when longer than ``max_plan_poses`` or larger than
        :data:`PLAN_BYTES_PER_POSE` a pose (e.g. long frame ids: 2,000 poses took 0.6 GB decoded), else decoded."""
        count, most = conv.path_pose_count(raw), self.settings.max_plan_poses
        if count > most:
            oversized = f"{count} poses (max_plan_poses {most})"
        elif len(raw) > PLAN_BYTES_FIXED + PLAN_BYTES_PER_POSE * max(count, 0):
            oversized = f"{len(raw)} bytes for {count} poses (long names?)"
        else:
            self.on_plan(deserialize_message(raw, Path))
            return
        self.counts["oversized"] += 1
        self.warnings.warn("oversized", f"ignored /plan: {oversized}, not decoded")

    def on_plan(self, msg: Path) -> None:
        """The initial path; its last pose becomes the goal (eq. 36-44 deform it from here on)."""
        try:
            points = conv.path_points_from_msg(msg)
            if len(points) < 2:
                raise InvalidRequest(f"plan has {len(points)} poses (need >= 2)")
            self.controller.set_path(points)
        except InvalidRequest as exc:
            self.counts["bad_plans"] += 1
            self.warnings.warn("plan", f"ignored /plan: {exc}")
            return
        self.path = points
        self._goal_logged = False
        self.get_logger().info(f"initial path with {len(points)} poses to ({points[-1, 0]:.2f}, {points[-1, 1]:.2f})")

    # ------------------------------------------------------------ the update
    def on_scan(self, msg: LaserScan) -> None:
        """Validate, then wait (at most until the next scan) for the odometry of the scan's time."""
        self.counts["scans"] += 1
        try:
            scan = conv.scan_from_msg(msg)
        except ScanError as exc:
            self.counts["dropped"] += 1
            self.warnings.warn("malformed", f"dropped malformed scan: {exc}")
            return
        if not self._in_time(scan.stamp, "scan"):
            return
        if self.counts["scans"] - self.counts["dropped"] - self.counts["future"] == 1:
            self.get_logger().info(f"receiving scans on {self.scan_topic}")
        self.last_valid_scan = time.monotonic()
        self._process_pending(force=True)
        self.pending = scan
        self._process_pending(force=not self.settings.odom_sync)

    def _process_pending(self, force: bool) -> None:
        """Run the update for the waiting scan once odometry stamped at or after it is in (or when forced).

        Pairing each scan with the odometry of its own time, whatever order the two
        arrive in, is what makes a replayed bag give the same commands every time.
        """
        scan = self.pending
        if scan is None or (not force and (self.odom_stamp is None or self.odom_stamp < scan.stamp)):
            return
        self.pending = None
        timeout = self.settings.stale_scan_timeout
        if self.odom_stamp is not None and self.odom_stamp < scan.stamp - timeout:
            lag = scan.stamp - self.odom_stamp
            self.warnings.warn("odom", f"odometry is {lag:.3f} s older than the scan: using it anyway")
        scan_age = self._now() - scan.stamp
        if scan_age > timeout:
            self.counts["stale"] += 1
            self.warnings.warn("stale", f"scan is {scan_age:.3f} s old (> {timeout} s): stopping the base")
            self._stop_base(scan.stamp)
            return
        if self.pose is None or not self.controller.has_goal:
            missing = "odometry" if self.pose is None else "a goal"
            self.warnings.warn("waiting", f"no {missing} yet: holding still")
            self._stop_base(scan.stamp)
            return
        try:
            self._update(scan)
        except (MaruError, ValueError) as exc:
            self.warnings.warn("update", f"update failed, stopping the base: {one_line(exc)}")
            self._stop_base(scan.stamp)

    def _update(self, scan: LaserScanData) -> None:
        out = self.controller.update(pose=self.pose, scan=scan)
        self.counts["updates"] += 1
        self.update_ms.append(out.update_time * 1e3)
        frame = self.settings.odom_frame
        self._send_command(out.v, out.w, scan.stamp)
        self.strip_pub.publish(conv.path_msg(np.asarray(out.strip), frame, scan.stamp))
        self._publish_arm(out, scan.stamp)
        if self.marker_pub.get_subscription_count() > 0:
            self.marker_pub.publish(conv.strip_markers(out.strip, out.obstacle_points, out.target, frame, scan.stamp))
        if out.reached_goal and not self._goal_logged:
            self.get_logger().info("goal reached")
            self._goal_logged = True

    def _publish_arm(self, out: ControlOutput, stamp: float) -> None:
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
        self.cmd_stamped_pub.publish(conv.twist_stamped_msg(v, w, self.settings.base_frame, stamp))
        self.base_stopped = v == 0.0 and w == 0.0

    def _stop_base(self, stamp: float | None = None) -> None:
        self._send_command(0.0, 0.0, self._now() if stamp is None else stamp)

    def on_watchdog(self) -> None:
        """Wall clock, both clock modes: stop the base once when no valid scan arrived for scan_timeout."""
        silent = time.monotonic() - self.last_valid_scan
        if not self.base_stopped and silent > self.settings.scan_timeout:
            self.warnings.warn(
                "silent",
                f"no scan for {silent:.2f} s (none valid within scan_timeout "
                f"{self.settings.scan_timeout} s): stopping the base",
            )
            self._stop_base()


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run maru_planner reactive_node``; exit code 2 on bad start-up input."""
    return run_node("reactive_node", ReactiveNode, args, farewell=lambda node: node.status())


if __name__ == "__main__":
    sys.exit(main())
