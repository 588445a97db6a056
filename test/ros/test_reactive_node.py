"""reactive_node: message conversions (no DDS) and the node end to end (a subprocess on loopback DDS).

``ReactiveClient`` is the test side of the node's topics; the replay and
closed-loop tests (test_reactive_replay.py) use it too. It sends inputs
lock-step (the next scan goes out once the last one's Twist is back), and
the node holds each scan until odometry of the scan's time has arrived, so
a scan is always paired with the odometry sent with it. For a node on sim
time (``use_sim_time``) it publishes ``/clock`` before each step, as
``ros2 bag play --clock`` does; DDS delivers the three in the order sent, and
the node's clock subscription is served before its others.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from reactive_helpers import (
    NODE_MODULE,
    OBSTACLE,
    REPO_ROOT,
    ReactiveClient,
    malformed_scans,
    odom,
    reactive_params_file,
    shipped_params,
    synthetic_scan,
)

from maru_planner.paths import config_path

pytestmark = pytest.mark.ros


def test_scan_conversion_round_trip_and_rep117_beams():
    from maru_planner.reactive import LaserScanData
    from maru_planner.ros import reactive_conversions as conv

    ranges = np.array([1.0, np.inf, np.nan, 0.01, 11.0, 2.5])
    data = LaserScanData(-0.5, 0.2, ranges, 0.05, 10.0, stamp=12.25)
    msg = conv.scan_msg(data, "laser_link", scan_time=0.1)
    assert msg.header.frame_id == "laser_link"
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (12, 250_000_000)
    assert msg.angle_max == pytest.approx(0.5)
    back = conv.scan_from_msg(msg)
    assert back.stamp == pytest.approx(12.25) and back.angle_max == pytest.approx(0.5)
    np.testing.assert_array_equal(np.isnan(back.ranges), np.isnan(ranges))
    assert back.ranges[0] == 1.0 and math.isinf(back.ranges[1])
    assert conv.scan_from_msg(msg, stamp=3.0).stamp == 3.0


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("angle_increment", 0.0, "angle_increment is 0"),
        ("angle_min", float("nan"), "angle_min is not finite"),
        ("angle_max", 2.0, "ranges but"),
        ("range_max", 0.01, "range limits"),
        ("intensities", [1.0, 2.0], "intensities"),
        ("ranges", [], "empty|ranges but"),
    ],
)
def test_malformed_scan_messages_raise_scan_error(field, value, match):
    from sensor_msgs.msg import LaserScan

    from maru_planner.reactive import ScanError
    from maru_planner.ros import reactive_conversions as conv

    msg = LaserScan()
    msg.angle_min, msg.angle_max, msg.angle_increment = -0.5, 0.5, 0.25
    msg.range_min, msg.range_max = 0.05, 10.0
    msg.ranges = [1.0] * 5
    conv.scan_from_msg(msg)
    setattr(msg, field, value)
    with pytest.raises(ScanError, match=match):
        conv.scan_from_msg(msg)


def test_pose_path_twist_and_arm_conversions():
    from maru_planner.ros import reactive_conversions as conv

    odom = conv.odom_msg((1.0, -2.0, 2.5), 0.3, -0.4, 7.5, "odom", "base_link")
    assert conv.pose_from_odom(odom) == pytest.approx((1.0, -2.0, 2.5))
    assert odom.child_frame_id == "base_link" and odom.twist.twist.angular.z == -0.4
    goal = conv.pose_stamped_msg((3.0, 4.0, -3.0), "map", 1.0)
    assert conv.pose_from_pose_stamped(goal) == pytest.approx((3.0, 4.0, -3.0))

    path = conv.path_msg(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), "odom", 2.0)
    points = conv.path_points_from_msg(path)
    np.testing.assert_allclose(points, [[0, 0, 0], [1, 0, math.pi / 2], [1, 1, math.pi / 2]], atol=1e-12)
    assert conv.path_points_from_msg(conv.path_msg(np.zeros((0, 2)), "odom", 0.0)).shape == (0, 3)

    twist = conv.twist_msg(0.2, -0.1)
    assert (twist.linear.x, twist.angular.z, twist.linear.y) == (0.2, -0.1, 0.0)
    traj = conv.arm_trajectory_msg(["a", "b"], np.array([0.1, 0.2]), np.array([0.01, -0.02]), 0.1, 3.0)
    assert traj.joint_names == ["a", "b"] and len(traj.points) == 1
    assert traj.points[0].positions == pytest.approx([0.1, 0.2])
    assert traj.points[0].velocities == pytest.approx([0.1, -0.2])
    assert traj.points[0].time_from_start.nanosec == 100_000_000

    markers = conv.strip_markers(np.array([[0, 0], [1, 0]]), np.array([[2.0, 1.0]]), np.array([1.0, 0.0]), "odom", 0)
    assert [m.ns for m in markers.markers] == ["strip", "vias", "obstacles", "target"]
    assert markers.markers[2].points[0].x == 2.0


def test_bag_records_decode_to_rclpy_messages():
    from maru_planner.ros import reactive_conversions as conv

    odom = conv.odom_msg((1.0, 2.0, 0.5), 0.0, 0.0, 1.0, "odom", "base_link")
    from rclpy.serialization import serialize_message

    back = conv.decode_bag_record("nav_msgs/msg/Odometry", serialize_message(odom))
    assert conv.pose_from_odom(back) == pytest.approx((1.0, 2.0, 0.5))
    with pytest.raises(ValueError, match="no rclpy class"):
        conv.decode_bag_record("no_such_msgs/msg/Nothing", b"")
    with pytest.raises(ValueError, match="not of the form"):
        conv.message_class("nav_msgs/Odometry")
    assert conv.message_class("visualization_msgs/msg/MarkerArray").__name__ == "MarkerArray"


def test_throttled_warnings_count_what_they_suppress():
    from maru_planner.ros.reactive_node import ThrottledWarnings

    class Logger:
        def __init__(self):
            self.lines = []

        def warning(self, text):
            self.lines.append(text)

        def error(self, text):
            self.lines.append("E " + text)

    logger, now = Logger(), [0.0]
    warnings = ThrottledWarnings(logger, period_s=3600.0, clock=lambda: now[0])
    for _ in range(5):
        warnings.warn("scan", "bad scan")
    warnings.warn("other", "other problem")
    warnings.error("boom", "callback failed")
    assert logger.lines == ["bad scan", "other problem", "E callback failed"]
    now[0] = 7200.0
    warnings.warn("scan", "bad scan")
    assert logger.lines[-1] == "bad scan (4 more since last warning)"


def test_shipped_config_declares_only_known_parameters():
    from maru_planner.ros.reactive_node import NODE_SPECS, ROS_PARAMETERS, STRIP_SPECS, strip_params_from_config

    params = shipped_params()
    known = set(STRIP_SPECS) | set(NODE_SPECS) | set(ROS_PARAMETERS)
    assert set(params) <= known, f"unknown keys in config/reactive.yaml: {set(params) - known}"
    strip = strip_params_from_config(config_path("reactive.yaml"))
    assert (strip.k_r, strip.k_c) == (0.5, 0.3)
    assert strip.strip == "modified"


# ---------------------------------------------------------------- the node as a process
@pytest.fixture(scope="module")
def reactive_node(node_process, tmp_path_factory):
    overrides = reactive_params_file(
        tmp_path_factory.mktemp("reactive_params"),
        scan_reliability="reliable",
        status_period=0.5,
        use_sim_time=True,
        scan_timeout=600.0,  # lock-step on a loaded machine: no watchdog stop between steps
    )
    args = ["--ros-args", "--params-file", str(config_path("reactive.yaml")), "--params-file", str(overrides)]
    return node_process(NODE_MODULE, args)


@pytest.fixture(scope="module")
def client(reactive_node, rclpy_session):
    from conftest import SpinningNode

    spinning = SpinningNode("reactive_node_test_client")
    client = ReactiveClient(spinning, process=reactive_node)
    client.wait_connected()
    yield client
    spinning.destroy()


def test_node_holds_still_without_a_goal(client, reactive_node):
    twist = client.step(odom((0.0, 0.0, 0.0), 1.0), synthetic_scan(1.0, [OBSTACLE]))
    assert (twist.linear.x, twist.angular.z) == (0.0, 0.0)
    assert client.strips == [], "no strip before there is a goal"
    assert reactive_node.alive()


def test_each_scan_gives_one_bounded_twist_strip_and_arm_command(client, reactive_node):
    from maru_planner.ros import reactive_conversions as conv

    limits = shipped_params()
    goal = conv.pose_stamped_msg((4.0, 0.0, 0.0), "odom", 1.05)
    client.send_and_confirm(client.goal_pub, goal, reactive_node, "goal (")
    twists = [client.step(odom((0.0, 0.0, 0.0), t), synthetic_scan(t, [OBSTACLE])) for t in (1.1, 1.2, 1.3, 1.4, 1.5)]
    assert all(abs(t.linear.x) <= limits["max_linear"] + 1e-9 for t in twists)
    assert all(abs(t.angular.z) <= limits["max_angular"] + 1e-9 for t in twists)
    assert any(t.linear.x > 0.0 for t in twists), "a free goal 4 m ahead must get the base moving"
    # the post sits left of the line to the goal: the commands turn right, away from it
    assert twists[-1].angular.z < 0.0
    assert client.spinning.wait_for(lambda: len(client.strips) >= 5 and len(client.arm) >= 5, timeout=60)
    assert [round(conv.stamp_to_s(s.header.stamp), 3) for s in client.strips[-5:]] == [1.1, 1.2, 1.3, 1.4, 1.5]
    strip = conv.path_points_from_msg(client.strips[-1])
    assert 3 <= len(strip) <= limits["num_vias"] and client.strips[-1].header.frame_id == "odom"
    assert strip[-1, :2] == pytest.approx((4.0, 0.0)), "a 4 m path fits in the strip: it ends at the goal"
    cx, cy, r = OBSTACLE
    assert np.min(np.hypot(strip[:, 0] - cx, strip[:, 1] - cy)) > r, "the strip must not pass through the post"
    arm = client.arm[-1]
    assert len(arm.joint_names) == 14 and arm.joint_names[0] == "left_arm_joint1"
    assert len(arm.points[0].positions) == 14
    assert all(abs(v) * 0.1 <= 0.05 + 1e-9 for v in arm.points[0].velocities), "arm steps within the step limit"


def test_malformed_scans_are_dropped_and_the_node_keeps_serving(client, reactive_node):
    for bad in malformed_scans(1.55):
        client.scan_pub.publish(bad)
    twist = client.step(odom((0.0, 0.0, 0.0), 1.6), synthetic_scan(1.6, [OBSTACLE]))
    assert twist.linear.x > 0.0
    assert reactive_node.alive()
    assert client.spinning.wait_for(lambda: "dropped malformed scan" in reactive_node.log(), timeout=10)


def test_a_stale_scan_stops_the_base(client, reactive_node):
    moving = client.step(odom((0.0, 0.0, 0.0), 1.7), synthetic_scan(1.7, [OBSTACLE]))
    assert moving.linear.x > 0.0
    stale = client.step(odom((0.0, 0.0, 0.0), 3.0), synthetic_scan(2.0, [OBSTACLE]))
    assert (stale.linear.x, stale.angular.z) == (0.0, 0.0)
    fresh = client.step(odom((0.0, 0.0, 0.0), 3.1), synthetic_scan(3.1, [OBSTACLE]))
    assert fresh.linear.x > 0.0
    assert client.spinning.wait_for(lambda: "stopping the base" in reactive_node.log(), timeout=10)


def test_status_counts_match_what_was_sent(client, reactive_node):
    """1 scan without goal + 5 + 1 + 3 (stale test) valid scans, 1 of them stale, 3 malformed: a Twist per valid one."""
    expected_twists = 1 + 5 + 1 + 3
    status = re.compile(r"scans (\d+), updates 8, dropped 3, stale 1; update median")
    assert client.spinning.wait_for(lambda: status.search(reactive_node.log()), timeout=60), reactive_node.log()[-2000:]
    scans = int(status.findall(reactive_node.log())[-1])
    handshakes = scans - 3 - expected_twists
    assert handshakes >= 1, "the handshake scans are answered too"
    answers = [client.stamped[k] for k in sorted(client.stamped) if k > 0]
    assert len(answers) == expected_twists
    assert client.plain_twists_end_with(answers), "cmd_vel carries the same commands, one per valid scan"


def test_sim_time_jumping_back_restarts_the_clock(client, reactive_node):
    """A bag played in a loop starts over: /clock goes back, and fresh scans after the jump are not stale."""
    assert client.step(odom((0.0, 0.0, 0.0), 3.2), synthetic_scan(3.2, [OBSTACLE])).linear.x > 0.0
    again = client.step(odom((0.0, 0.0, 0.0), 1.25), synthetic_scan(1.25, [OBSTACLE]))
    assert again.linear.x > 0.0
    assert "time jumped back" in reactive_node.log()


# ---------------------------------------------------------------- watchdog, bad parameters, launch file
@pytest.mark.parametrize("sim_time", [False, True], ids=["wall_time", "sim_time"])
def test_wall_clock_watchdog_stops_the_base_when_scans_stop(node_process, rclpy_session, tmp_path, sim_time):
    """In both clock modes: no valid scan for scan_timeout s of wall time -> one zero Twist, without a scan.

    On sim time the /clock stops with the scans (a paused bag), so only a wall-clock watchdog notices.
    """
    from conftest import SpinningNode

    from maru_planner.ros import reactive_conversions as conv

    ns = f"/watchdog_{'sim' if sim_time else 'wall'}"
    params = reactive_params_file(
        tmp_path, scan_reliability="reliable", use_sim_time=sim_time, scan_timeout=3.0, stale_scan_timeout=3.0
    )  # room for a loaded machine's delays
    process = node_process(
        NODE_MODULE, ["--ros-args", "-r", f"__ns:={ns}", "-r", f"/clock:={ns}/clock", "--params-file", str(params)]
    )
    spinning = SpinningNode(f"watchdog_client_{ns[10:]}")
    try:
        client = ReactiveClient(spinning, namespace=ns, process=process, sim_time=sim_time)
        client.wait_connected()
        client.send_and_confirm(client.goal_pub, conv.pose_stamped_msg((4.0, 0.0, 0.0), "odom", 0.0), process, "goal (")
        now = 100.0 if sim_time else spinning.node.get_clock().now().nanoseconds / 1e9
        moving = client.step(odom((0.0, 0.0, 0.0), now), synthetic_scan(now, [OBSTACLE]))
        assert moving.linear.x > 0.0, "a fresh scan on the node clock gets the base moving"
        assert client.plain_twists_end_with([moving])
        moving_count = client.twist_count()
        # no more scans: the watchdog (not a scan) must send a zero Twist
        assert spinning.wait_for(lambda: client.twist_count() > moving_count, timeout=60), process.log()[-2000:]
        last = client.twists[-1]
        assert (last.linear.x, last.angular.z) == (0.0, 0.0)
        assert "no scan for" in process.log()
        old = now - 10.0
        stale = client.step(
            odom((0.0, 0.0, 0.0), old), synthetic_scan(old, [OBSTACLE]), clock_ns=round((now + 0.1) * 1e9)
        )
        assert (stale.linear.x, stale.angular.z) == (0.0, 0.0), "a scan 10 s behind the node clock is stale"
        assert process.alive()
    finally:
        spinning.destroy()


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"strip": "elastic"}, "'strip'"),
        ({"k_r": "strong"}, "'k_r'"),
        ({"d_safe": 1}, "'d_safe' must be a double"),
        ({"stale_scan_timeout": -1.0}, "'stale_scan_timeout'"),
        ({"scan_reliability": "sometimes"}, "'scan_reliability'"),
        ({"num_vias": 2}, "'num_vias'"),
        ({"beam_window": [50, 10]}, "beam_window must be"),
    ],
)
def test_bad_parameters_stop_the_node_with_one_line(tmp_path, override, message):
    import subprocess
    import sys

    params = reactive_params_file(tmp_path, **override)
    result = subprocess.run(
        [sys.executable, "-m", NODE_MODULE, "--ros-args", "--params-file", str(params)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=REPO_ROOT,
    )
    assert result.returncode == 2
    lines = (result.stderr + result.stdout).strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in lines[0], lines
    assert lines[0].startswith("reactive_node: cannot start:") and message in lines[0], lines[0]


def test_params_file_that_is_not_yaml_stops_the_node_without_a_traceback(tmp_path):
    import subprocess
    import sys

    params = tmp_path / "broken.yaml"
    params.write_text("/**:\n  ros__parameters:\n    k_r: [unclosed\n")
    result = subprocess.run(
        [sys.executable, "-m", NODE_MODULE, "--ros-args", "--params-file", str(params)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=REPO_ROOT,
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "reactive_node: cannot start: " in result.stderr


def test_launch_file_starts_the_node_with_the_shipped_config(monkeypatch):
    """launch / launch_ros are not installed here: stand-ins record what the launch file asks for."""
    import importlib.util
    import sys
    import types

    class Recorder:
        def __init__(self, *args, **kwargs):
            self.args, self.kwargs = args, kwargs

    fakes = {
        "launch": types.SimpleNamespace(LaunchDescription=Recorder),
        "launch.actions": types.SimpleNamespace(DeclareLaunchArgument=Recorder),
        "launch.conditions": types.SimpleNamespace(IfCondition=Recorder),
        "launch.substitutions": types.SimpleNamespace(
            LaunchConfiguration=lambda name: f"<{name}>", PythonExpression=lambda parts: "".join(parts)
        ),
        "launch_ros.actions": types.SimpleNamespace(Node=Recorder),
        "ament_index_python.packages": types.SimpleNamespace(get_package_share_directory=lambda _: str(REPO_ROOT)),
    }
    for name, module in fakes.items():
        monkeypatch.setitem(sys.modules, name, module)
    monkeypatch.delitem(sys.modules, "maru_planner.ros.launch_args", raising=False)  # rebuilt on the stand-ins
    spec = importlib.util.spec_from_file_location("reactive_launch", REPO_ROOT / "launch" / "reactive.launch.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    description = module.generate_launch_description()
    *arguments, rviz, node = description.args[0]
    assert rviz.kwargs["executable"] == "rviz2"  # test_launch_files.py checks it with the other launch files
    defaults = {a.args[0]: a.kwargs["default_value"] for a in arguments}
    assert Path(defaults["params_file"]) == config_path("reactive.yaml")
    assert node.kwargs["executable"] == "reactive_node" and node.kwargs["name"] == "reactive_node"
    file, overrides = node.kwargs["parameters"]
    assert file == "<params_file>"
    assert overrides == {"strip": "<strip>", "use_sim_time": "<use_sim_time>", "autostart": "<autostart>"}
    assert defaults["use_sim_time"] == "false"
    setup_py = REPO_ROOT / "setup.py"
    assert "reactive_node = maru_planner.ros.reactive_node:main" in setup_py.read_text()
    remapped = dict(node.kwargs["remappings"])
    assert set(remapped) == {"scan", "odom", "plan", "goal_pose", "cmd_vel"}
    assert {defaults[v.strip("<>")] for v in remapped.values()} == set(remapped), "remappings default to identity"
