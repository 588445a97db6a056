"""mujoco_sim_node (issue 38): lock-step with the real reactive_node (use_sim_time), deterministic for a seed;
NaN in cmd_vel; a controller that stops publishing (the base stops after cmd_timeout and the status says so).

Two lock-step pairs (sim + reactive_node, namespaces a and b, each pair on its own clock topic) drive world 0
with the same seed at the same time; a third sim (namespace c) is driven by the test itself.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from maru_planner.paths import config_path

STEPS = 30  # lock-step periods compared (3 s of sim time)
STRIP = [  # reactive_node overrides for the 720-beam laser and the Jackal-like base
    "-p", "use_sim_time:=true", "-p", "scan_reliability:=reliable", "-p", "arm_enabled:=false",
    "-p", "publish_arm:=false", "-p", "beam_window:=[0, 719]", "-p", "laser_pose:=[0.055, 0.0, 0.0]",
    "-p", "robot_radius:=0.25", "-p", "d_safe:=0.12", "-p", "max_linear:=1.0", "-p", "via_spacing:=0.2",
    "-p", "scan_timeout:=30.0", "-p", "stale_scan_timeout:=5.0",
]  # fmt: skip


def _remap_clock(ns: str) -> list[str]:
    return ["-r", f"__ns:=/{ns}", "-r", f"/clock:=/{ns}/clock"]


def _sim_args(ns: str, *extra: str) -> list[str]:
    args = ["--ros-args", "--params-file", str(config_path("mujoco_sim.yaml")), *_remap_clock(ns)]
    return [*args, "-p", "world:=0", "-p", "seed:=3", *extra]


class StatusLog:
    """The ~/status lines of one sim node, parsed."""

    def __init__(self, node, ns: str):
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        self.lines: list[dict] = []
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        node.create_subscription(String, f"/{ns}/mujoco_sim_node/status", self._on, qos)

    def _on(self, msg) -> None:
        self.lines.append(json.loads(msg.data))

    def at_step(self, step: int) -> dict | None:
        return next((s for s in self.lines if s["steps"] == step), None)


@pytest.fixture(scope="module")
def pairs(node_process, tester):
    """Reactive nodes a and b given the goal 10 m ahead and a straight path, then their sims started."""
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path

    from maru_planner.ros import reactive_conversions as conv

    reactive = {
        ns: node_process(
            "maru_planner.ros.reactive_node",
            ["--ros-args", "--params-file", str(config_path("reactive.yaml")), *_remap_clock(ns), *STRIP],
        )
        for ns in ("a", "b")
    }
    logs = {ns: StatusLog(tester.node, ns) for ns in ("a", "b", "c")}
    path = np.column_stack([np.linspace(0.0, 10.0, 51), np.zeros(51)])
    for ns, proc in reactive.items():
        goal_pub = tester.node.create_publisher(PoseStamped, f"/{ns}/goal_pose", 1)
        plan_pub = tester.node.create_publisher(Path, f"/{ns}/plan", 1)
        assert tester.wait_for(
            lambda g=goal_pub, p=plan_pub: g.get_subscription_count() and p.get_subscription_count(), 60
        )
        while "initial path" not in proc.log():  # the goal and path are in before the sim's first scan
            goal_pub.publish(conv.pose_stamped_msg((10.0, 0.0, 0.0), "odom", 0.0))
            plan_pub.publish(conv.path_msg(path, "odom", 0.0))
            assert tester.wait_for(lambda p=proc: "initial path" in p.log(), 2.0) or proc.alive(), proc.log()
    sims = {ns: node_process("maru_planner.ros.mujoco_sim_node", _sim_args(ns)) for ns in ("a", "b")}
    sims["c"] = node_process("maru_planner.ros.mujoco_sim_node", _sim_args("c", "-p", "lockstep_wait:=0.05"))
    yield sims, reactive, logs
    for proc in (*sims.values(), *reactive.values()):
        assert proc.alive(), proc.log()


def test_lockstep_with_reactive_node_drives_and_is_deterministic(pairs, tester):
    sims, reactive, logs = pairs
    for ns in ("a", "b"):  # the sims may run ahead of this subscriber's discovery: compare the steps both saw
        assert tester.wait_for(lambda n=ns: logs[n].lines and logs[n].lines[-1]["steps"] >= STEPS, 25.0), (
            sims[ns].log() + reactive[ns].log()
        )
    # one sim may be far ahead when this subscriber first heard it (a loaded machine): wait until both have passed
    # the later of the two first-heard steps, so they share a stretch of steps to compare
    shared_from = max(logs[ns].lines[0]["steps"] for ns in ("a", "b")) + STEPS // 3
    for ns in ("a", "b"):
        assert tester.wait_for(lambda n=ns: logs[n].lines[-1]["steps"] >= shared_from, 60.0), sims[ns].log()
    seen_a = {line["steps"]: line for line in list(logs["a"].lines)}
    seen_b = {line["steps"]: line for line in list(logs["b"].lines)}
    common = sorted(set(seen_a) & set(seen_b))
    assert common, (sorted(seen_a)[:3], sorted(seen_b)[:3])
    for step in common[:: max(1, len(common) // 10)]:
        a, b = seen_a[step], seen_b[step]
        assert a["time"] == pytest.approx(step * 0.1 + 0.1)  # one period before the first command
        assert a["truth"] == b["truth"] and a["odom"] == b["odom"]  # same seed, lock-step: the same run
    a = seen_a[common[-1]]
    moved = math.hypot(a["truth"][0] + 2.25, a["truth"][1] - 3.0)
    assert moved > 0.3, a  # the real reactive_node drove the simulated base toward the goal
    assert a["silent_steps"] == 0 and a["cmd_timeouts"] == 0 and a["nan_commands"] == 0


def test_nan_cmd_vel_stops_the_base_and_a_silent_controller_times_out(pairs, tester):
    from geometry_msgs.msg import Twist
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    sims, _reactive, logs = pairs
    log = logs["c"]
    pub = tester.node.create_publisher(
        Twist, "/c/cmd_vel", QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    )
    assert tester.wait_for(lambda: pub.get_subscription_count() > 0 and log.lines, 25.0), sims["c"].log()

    def drive(v: float, w: float, steps: int) -> dict:
        for _ in range(steps):
            before = log.lines[-1]["steps"]
            pub.publish(Twist(linear=type(Twist().linear)(x=v), angular=type(Twist().angular)(z=w)))
            assert tester.wait_for(lambda b=before: log.lines[-1]["steps"] > b, 10.0), sims["c"].log()
        return log.lines[-1]

    moving = drive(0.6, 0.0, 10)
    assert moving["nan_commands"] == 0
    stopped = drive(math.nan, 0.0, 10)
    assert stopped["nan_commands"] == 10
    assert math.dist(stopped["truth"][:2], drive(math.nan, 0.0, 5)["truth"][:2]) < 0.01  # at rest, still serving
    resumed = drive(0.6, 0.0, 5)
    assert math.dist(resumed["truth"][:2], stopped["truth"][:2]) > 0.05
    # the controller falls silent: the sim advances on its own and the base stops after cmd_timeout
    assert tester.wait_for(lambda: log.lines[-1]["cmd_timeouts"] >= 1 and log.lines[-1]["silent_steps"] >= 15, 20.0)
    last = log.lines[-1]
    assert last["first_timeout_s"] == pytest.approx(resumed["time"] + 0.5, abs=0.11)
    assert "the base stopped" in sims["c"].log()
    later = log.lines[-1]
    assert math.dist(later["truth"][:2], log.lines[-6]["truth"][:2]) < 0.01  # at rest
