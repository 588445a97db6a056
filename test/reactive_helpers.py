"""The test side of reactive_node's topics, shared by the ros and hostile lanes: ``ReactiveClient`` and the messages
it sends (synthetic scans, odometry, malformed scans, hostile scans for hypothesis).

``ReactiveClient`` sends inputs lock-step (the next scan goes out once the last one's Twist is back), and the node
holds each scan until odometry of the scan's time has arrived, so a scan is always paired with the odometry sent
with it. For a node on sim time (``use_sim_time``) it publishes ``/clock`` before each step, as
``ros2 bag play --clock`` does; DDS delivers the three in the order sent, and the node's clock subscription is
served before its others.
"""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np
import yaml
from hypothesis import strategies as st

from maru_planner.paths import config_path

NODE_MODULE = "maru_planner.ros.reactive_node"
NODE_KEY = "/**"  # the params file applies to reactive_node in any namespace
REPO_ROOT = Path(__file__).resolve().parents[1]


def reactive_params_file(tmp_path: Path, **overrides) -> Path:
    """config/reactive.yaml with ``overrides`` applied, written to a temporary file."""
    data = yaml.safe_load(config_path("reactive.yaml").read_text())
    data[NODE_KEY]["ros__parameters"].update(overrides)
    path = tmp_path / f"reactive_{len(list(tmp_path.glob('reactive_*.yaml')))}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def start_namespaced_node(node_process, tmp_path: Path, namespace: str, **overrides):
    """reactive_node on sim time in ``namespace`` (its /clock remapped there), config/reactive.yaml + ``overrides``."""
    params = reactive_params_file(tmp_path, scan_reliability="reliable", use_sim_time=True, **overrides)
    remaps = ["-r", f"__ns:={namespace}", "-r", f"/clock:={namespace}/clock"]
    return node_process(NODE_MODULE, ["--ros-args", *remaps, "--params-file", str(params)])


def client_with_goal(name: str, namespace: str, process, goal=(4.0, 0.0, 0.0)):
    """A connected ReactiveClient on a new spinning node ``name`` whose ``goal`` the node at ``process`` confirmed;
    a generator for module fixtures (the spinning node is destroyed after the yield)."""
    from conftest import SpinningNode

    from maru_planner.ros import reactive_conversions as conv

    spinning = SpinningNode(name)
    client = ReactiveClient(spinning, namespace=namespace, process=process)
    client.wait_connected()
    client.send_and_confirm(client.goal_pub, conv.pose_stamped_msg(goal, "odom", 0.0), process, "goal (")
    yield client
    spinning.destroy()


def shipped_params() -> dict:
    return yaml.safe_load(config_path("reactive.yaml").read_text())[NODE_KEY]["ros__parameters"]


class ReactiveClient:
    """Publishers for the node's inputs and recorders of its outputs (one namespace)."""

    def __init__(self, spinning, namespace: str = "", process=None, sim_time: bool = True):
        """``sim_time``: publish ``<namespace>/clock`` before each step (start the node with
        ``use_sim_time`` and, in a namespace, ``-r /clock:=<namespace>/clock``)."""
        from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
        from nav_msgs.msg import Odometry, Path
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan
        from trajectory_msgs.msg import JointTrajectory
        from visualization_msgs.msg import MarkerArray

        reliable = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
        self.spinning = spinning
        self.process = process  # the node under test, for its log in failure messages
        node = self.node = spinning.node
        self._lock = threading.Lock()
        self.twists: list = []
        self.stamped: dict[int, object] = {}  # scan stamp (ns) -> the Twist answering it
        self.strips: list = []
        self.arm: list = []
        self.markers: list = []
        # Created in this order on purpose: discovery announces endpoints in creation order, so once the
        # node has matched the last writer (scan) and the last reader (cmd_vel_stamped), it has the others.
        self.clock_pub = node.create_publisher(Clock, f"{namespace}/clock", reliable) if sim_time else None
        self.odom_pub = node.create_publisher(Odometry, f"{namespace}/odom", reliable)
        self.plan_pub = node.create_publisher(Path, f"{namespace}/plan", reliable)
        self.goal_pub = node.create_publisher(PoseStamped, f"{namespace}/goal_pose", reliable)
        self.scan_pub = node.create_publisher(LaserScan, f"{namespace}/scan", reliable)
        private = f"{namespace}/reactive_node"
        self._subscriptions = [
            node.create_subscription(Twist, f"{namespace}/cmd_vel", self._keep(self.twists), reliable),
            node.create_subscription(Path, f"{private}/strip", self._keep(self.strips), reliable),
            node.create_subscription(JointTrajectory, f"{private}/arm_command", self._keep(self.arm), reliable),
            node.create_subscription(MarkerArray, f"{private}/markers", self._keep(self.markers), reliable),
            node.create_subscription(TwistStamped, f"{private}/cmd_vel_stamped", self._keep_stamped, reliable),
        ]

    def _keep(self, store: list):
        def callback(msg):
            with self._lock:
                store.append(msg)

        return callback

    def _keep_stamped(self, msg) -> None:
        from maru_planner.ros.reactive_conversions import stamp_to_ns

        with self._lock:
            self.stamped[stamp_to_ns(msg.header.stamp)] = msg.twist

    def wait_connected(self, timeout: float = 90.0) -> None:
        pubs = (self.scan_pub, self.odom_pub, self.plan_pub, self.goal_pub, *filter(None, [self.clock_pub]))
        ok = self.spinning.wait_for(lambda: all(p.get_subscription_count() > 0 for p in pubs), timeout=timeout)
        assert ok, "reactive_node did not subscribe to scan, odom, plan and goal_pose"
        subs = self._subscriptions
        ok = self.spinning.wait_for(lambda: all(s.get_publisher_count() > 0 for s in subs), timeout=timeout)
        assert ok, "reactive_node's cmd_vel, strip, arm_command, markers, cmd_vel_stamped publishers not discovered"
        self._handshake()

    def _handshake(self, attempts: int = 60) -> None:
        """Send odometry and a scan stamped 0 until their answer comes back.

        Discovery is not symmetric: we can see the node's endpoints before the node knows ours, and
        a volatile endpoint misses what is sent meanwhile. An answer to a scan (a zero Twist: there
        is no goal yet) proves both directions are matched. Answers are told apart by their stamp.
        """
        from sensor_msgs.msg import LaserScan

        from maru_planner.ros import reactive_conversions as conv

        scan = LaserScan()
        scan.angle_min, scan.angle_max, scan.angle_increment = -0.1, 0.1, 0.1
        scan.range_min, scan.range_max, scan.ranges = 0.05, 10.0, [float("inf")] * 3
        for _ in range(attempts):
            self.odom_pub.publish(conv.odom_msg((0.0, 0.0, 0.0), 0.0, 0.0, 0.0, "odom", "base_link"))
            self.scan_pub.publish(scan)
            if self.spinning.wait_for(lambda: 0 in self.stamped and self.twist_count() > 0, timeout=1.0):
                return
        raise AssertionError("reactive_node never answered the handshake scan" + self._log_tail())

    def _log_tail(self) -> str:
        return f"; node log:\n{self.process.log()[-3000:]}" if self.process else ""

    def send_and_confirm(self, publisher, msg, process, marker: str, attempts: int = 60) -> None:
        """Publish a goal or plan until the node's log shows it was applied (``marker`` once more).

        Re-sending is harmless: both only (re)set the initial path, and no scan is sent in between.
        """
        before = process.log().count(marker)
        for _ in range(attempts):
            publisher.publish(msg)
            if self.spinning.wait_for(lambda: process.log().count(marker) > before, timeout=1.0):
                return
        raise AssertionError(f"reactive_node did not apply {publisher.topic_name}:\n{process.log()[-1500:]}")

    def twist_count(self) -> int:
        with self._lock:
            return len(self.twists)

    def publish_clock(self, stamp_ns: int) -> None:
        from rosgraph_msgs.msg import Clock

        from maru_planner.ros.reactive_conversions import ns_to_stamp

        self.clock_pub.publish(Clock(clock=ns_to_stamp(stamp_ns)))

    def step(self, odom, scan, timeout: float = 60.0, clock_ns: int | None = None):
        """Send the clock (sim time: ``clock_ns``, else the newer of the two stamps), odometry and a scan;
        return the command (Twist) that answers the scan."""
        from maru_planner.ros.reactive_conversions import stamp_to_ns

        stamp = stamp_to_ns(scan.header.stamp)
        assert stamp not in self.stamped, "scan stamps must be unique within a test"
        if self.clock_pub is not None:
            newest = max(stamp, stamp_to_ns(odom.header.stamp) if odom is not None else stamp)
            self.publish_clock(newest if clock_ns is None else clock_ns)
        if odom is not None:
            self.odom_pub.publish(odom)
        self.scan_pub.publish(scan)
        ok = self.spinning.wait_for(lambda: stamp in self.stamped, timeout=timeout)
        assert ok, f"no command for the scan stamped {stamp} ns" + self._log_tail()
        with self._lock:
            return self.stamped[stamp]

    def plain_twists_end_with(self, commands: list, timeout: float = 60.0) -> bool:
        """The cmd_vel stream ends with ``commands`` (the answers to the scans, in order)."""
        n = len(commands)
        ok = self.spinning.wait_for(lambda: self.twist_count() >= n, timeout=timeout)
        with self._lock:
            tail = [(t.linear.x, t.angular.z) for t in self.twists[-n:]]
        return ok and tail == [(t.linear.x, t.angular.z) for t in commands]


# ---------------------------------------------------------------- conversions, no DDS


def synthetic_scan(stamp: float, circles=(), pose=(0.0, 0.0, 0.0), laser_x: float = 0.22, beams: int = 361):
    """An LMS200-like scan (180 deg, 0.5 deg) from a robot at ``pose`` seeing circles (x, y, r) in the world."""
    from maru_planner.reactive import LaserScanData
    from maru_planner.ros import reactive_conversions as conv

    angles = -math.pi / 2 + np.arange(beams) * (math.pi / (beams - 1))
    c, s = math.cos(pose[2]), math.sin(pose[2])
    origin = np.array([pose[0] + c * laser_x, pose[1] + s * laser_x])
    dirs = np.stack([np.cos(angles + pose[2]), np.sin(angles + pose[2])], axis=1)
    ranges = np.full(beams, np.inf)
    for cx, cy, r in circles:
        rel = np.array([cx, cy]) - origin
        along = dirs @ rel
        miss2 = rel @ rel - along**2
        hit = (miss2 <= r * r) & (along > 0)
        ranges[hit] = np.minimum(ranges[hit], along[hit] - np.sqrt(r * r - miss2[hit]))
    data = LaserScanData(-math.pi / 2, math.pi / (beams - 1), ranges, 0.05, 10.0, stamp=stamp)
    return conv.scan_msg(data, "laser_link", scan_time=0.1)


def odom(pose, stamp):
    from maru_planner.ros import reactive_conversions as conv

    return conv.odom_msg(pose, 0.0, 0.0, stamp, "odom", "base_link")


def malformed_scans(stamp: float):
    zero_increment = synthetic_scan(stamp)
    zero_increment.angle_increment = 0.0
    nan_angle = synthetic_scan(stamp)
    nan_angle.angle_min = float("nan")
    short = synthetic_scan(stamp)
    short.ranges = short.ranges[:100]
    return [zero_increment, nan_angle, short]


OBSTACLE = (1.6, 0.25, 0.3)  # a post a little left of the straight line to the goal


FLOAT32 = st.floats(width=32)  # LaserScan fields are float32 on the wire: any of them, NaN and inf included


@st.composite
def laser_scans(draw):
    from sensor_msgs.msg import LaserScan

    msg = LaserScan()
    msg.header.stamp.sec = draw(st.integers(0, 2**31 - 1))
    if draw(st.booleans()):  # a plausible geometry, hostile details
        count = draw(st.integers(1, 400))
        msg.angle_min = draw(st.floats(-3.0, 3.0))
        msg.angle_increment = draw(st.floats(1e-4, 0.1))
        msg.angle_max = msg.angle_min + msg.angle_increment * (count - 1)
        msg.range_min = draw(st.floats(0.0, 1.0))
        msg.range_max = draw(st.floats(0.0, 100.0))
        msg.ranges = draw(st.lists(FLOAT32, min_size=count, max_size=count))
    else:  # anything at all
        msg.angle_min, msg.angle_max, msg.angle_increment = draw(FLOAT32), draw(FLOAT32), draw(FLOAT32)
        msg.range_min, msg.range_max = draw(FLOAT32), draw(FLOAT32)
        msg.ranges = draw(st.lists(FLOAT32, max_size=50))
    msg.intensities = draw(st.lists(FLOAT32, max_size=3))
    return msg
