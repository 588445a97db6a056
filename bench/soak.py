"""Soak: all three nodes under mixed traffic for ``--duration`` seconds; memory, crashes, lost answers, latency drift.

Starts planning_node, reactive_node and base_planner_node (shipped config files) as their own processes on
loopback DDS, and an empty std_srvs/Trigger server as the baseline peer. This process then sends, on a fixed
schedule: plan_motion calls (a small right-arm move), plan_motion action goals (every other one cancelled right
after acceptance), scene edits (add / move / remove a box), 10 Hz scans + odometry to reactive_node (with a goal),
base plans (plan_base_path on paper 002's medium map) and trigger calls; 5 % of the messages are hostile (a NaN
plan goal, a malformed obstacle, a malformed scan, an oversized /plan, a base goal outside the map).

Every second it samples each node's RSS (the planning node with its worker processes). Summary:

- ``duration_s``; ``rss_growth``: the largest node's relative RSS growth from the end of the warm-up (the first
  5 minutes, or the first sixth of a shorter run) to the end; ``crashes``: nodes that exited;
- ``lost``: requests or goals without an answer within their budget + 30 s;
- ``p99_drift``: p99 plan_motion latency of the last window / the first window - 1 (windows of 5 minutes, or a
  third of a shorter run); the trigger peer's drift beside it (what the machine alone drifted).

Targets (issue 36, for the 30-minute run): rss_growth <= 5 %, 0 crashes, 0 lost, |p99_drift| <= 20 %.

    .venv/bin/python bench/soak.py [--duration 1800] [--quick] [--out DIR]   (--quick: 60 s, under bench/results/quick/)

The suite runs the 60-second version (test/ros/test_soak_minute.py).
"""

from __future__ import annotations

import argparse
import math
import random
import subprocess
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from _common import PAPER_START, RESULTS, log, start_python, write_results

from maru_planner.paths import config_path
from maru_planner.ros.env import configure_loopback_dds

NAME = "soak"
FULL_DURATION_S = 1800.0
REPORT_PERIOD_S = 60.0  # a progress line this often
WARM_UP_S, WINDOW_S = 300.0, 300.0  # the issue's: growth after the first 5 minutes, p99 of the first/last 5
HOSTILE_SHARE = 0.05
ANSWER_GRACE_S = 30.0  # s past a request's budget before it counts as lost
TARGETS = {"rss_growth": 0.05, "crashes": 0, "lost": 0, "p99_drift": 0.20}
NODES = {
    "planning_node": ("maru_planner.ros.planning_node", "planner.yaml"),
    "reactive_node": ("maru_planner.ros.reactive_node", "reactive.yaml"),
    "base_planner_node": ("maru_planner.ros.base_planner_node", "base_planner.yaml"),
}
# what is sent how often (s); the hostile variant replaces 5 % of them
PERIODS = {"plan": 0.25, "goal": 1.0, "scene": 1.0, "scan": 0.1, "base_plan": 1.0, "trigger": 0.25}
PLAN_BUDGET, BASE_BUDGET = 5.0, 5.0
TRIGGER_SERVER = (
    "import rclpy\nfrom rclpy.executors import ExternalShutdownException\nfrom std_srvs.srv import Trigger\n"
    "from maru_planner.ros.env import configure_loopback_dds\nconfigure_loopback_dds()\nrclpy.init()\n"
    "node = rclpy.create_node('soak_trigger_server')\n"
    "node.create_service(Trigger, 'soak_trigger', lambda request, response: response)\n"
    "try:\n    rclpy.spin(node)\nexcept (KeyboardInterrupt, ExternalShutdownException):\n    pass\n"
)


@dataclass
class Ledger:
    """Every request sent (kind, sent at, budget) and its answer time; RSS samples per node."""

    t0: float = field(default_factory=time.monotonic)
    sent: dict[int, tuple[str, float, float]] = field(default_factory=dict)
    answered: dict[int, float] = field(default_factory=dict)
    rss: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)
    _ids: int = 0

    def track(self, kind: str, future, budget: float) -> None:
        """Record ``future`` (an rclpy Future of an answer) sent now."""
        with self.lock:
            self._ids += 1
            key = self._ids
            self.sent[key] = (kind, time.monotonic() - self.t0, budget)
        future.add_done_callback(lambda _f: self._answer(key))

    def _answer(self, key: int) -> None:
        with self.lock:
            self.answered[key] = time.monotonic() - self.t0

    def count(self, kind: str) -> None:
        with self.lock:
            self.counts[kind] = self.counts.get(kind, 0) + 1

    def latencies(self, kind: str) -> np.ndarray:
        """(sent at, seconds to the answer) of the answered requests of ``kind``."""
        with self.lock:
            rows = [
                (t, self.answered[k] - t) for k, (kd, t, _) in self.sent.items() if kd == kind and k in self.answered
            ]
        return np.array(rows).reshape(-1, 2)

    def unanswered(self) -> dict[str, int]:
        """Requests without an answer yet, by kind."""
        with self.lock:
            late = [kind for key, (kind, _, _) in self.sent.items() if key not in self.answered]
        return {kind: late.count(kind) for kind in sorted(set(late))}


def report_progress(now: float, duration: float, sent: dict[str, int], ledger: Ledger) -> None:
    """One line on stderr: time, requests sent, those still unanswered, each node's latest RSS."""
    waiting = sum(ledger.unanswered().values())
    memory = ", ".join(f"{name} {samples[-1][1]:.0f} MB" for name, samples in ledger.rss.items() if samples)
    log(f"{now:.0f}/{duration:.0f} s: {sum(sent.values())} requests sent, {waiting} awaiting an answer; RSS {memory}")


def rss_mb(pid: int, with_children: bool = False) -> float:
    """Resident memory of ``pid`` (and its descendants: the planning node's worker processes), MB."""
    pids = [pid] + (descendants(pid) if with_children else [])
    total = 0.0
    for p in pids:
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1]) / 1024.0
        except OSError:  # ended meanwhile
            continue
    return total


def descendants(pid: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parent = int(stat.read_text().rsplit(") ", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(parent, []).append(int(stat.parent.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


class Traffic:
    """The clients and publishers of this process and the messages they send (module doc)."""

    def __init__(self, node, ledger: Ledger, seed: int = 36):
        from geometry_msgs.msg import PoseStamped
        from nav_msgs.msg import OccupancyGrid, Odometry
        from nav_msgs.msg import Path as PathMsg
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import LaserScan
        from std_srvs.srv import Trigger

        from maru_planner.ros.planning_client import REPLY_QOS, PlanningClient
        from maru_planner_interfaces.srv import PlanBasePath

        self.node, self.ledger, self.random = node, ledger, random.Random(seed)
        self.planning = PlanningClient(node=node)
        self.base_client = node.create_client(PlanBasePath, "plan_base_path", qos_profile=REPLY_QOS)
        self.trigger_client = node.create_client(Trigger, "soak_trigger", qos_profile=REPLY_QOS)
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self.map_pub = node.create_publisher(OccupancyGrid, "map", latched)
        self.scan_pub = node.create_publisher(LaserScan, "scan", 5)
        self.odom_pub = node.create_publisher(Odometry, "odom", 10)
        self.goal_pub = node.create_publisher(PoseStamped, "goal_pose", 10)
        self.plan_pub = node.create_publisher(PathMsg, "plan", 1)
        self.goals: list = []
        self.oversized_plan = self._oversized_plan()

    def connect(self) -> None:
        from maru_planner.base.scenes import table1
        from maru_planner.ros import reactive_conversions as conv
        from maru_planner.ros.base_conversions import grid_to_msg

        self.planning.wait_until_ready(timeout=180.0)
        for client in (self.base_client, self.trigger_client):
            if not client.wait_for_service(timeout_sec=120.0):
                raise RuntimeError(f"{client.srv_name} never appeared")
        grid = table1("medium")
        self.map_pub.publish(grid_to_msg(grid, grid.occupied, self.node.get_clock().now().to_msg(), "map"))
        self.goal_pub.publish(conv.pose_stamped_msg((4.0, 0.0, 0.0), "odom", self._now()))

    def _now(self) -> float:
        return self.node.get_clock().now().nanoseconds / 1e9

    def _hostile(self) -> bool:
        return self.random.random() < HOSTILE_SHARE

    def _oversized_plan(self) -> bytes:
        from rclpy.serialization import serialize_message

        from maru_planner.ros import reactive_conversions as conv

        points = np.column_stack([np.linspace(0.0, 4.0, 20_000), np.zeros(20_000), np.zeros(20_000)])
        return serialize_message(conv.path_msg(points, "odom", 0.0))

    # --- one message of each kind ------------------------------------------------------------
    def plan(self, i: int) -> None:
        from maru_planner.ros.planning_client import plan_request, send_request

        goal = dict(PAPER_START, r_arm_j4=PAPER_START["r_arm_j4"] + 0.2 + 0.001 * (i % 100))
        if self._hostile():
            goal["r_arm_j4"] = math.nan
            self.ledger.count("hostile")
        request = plan_request(goal, start=PAPER_START, planner_id="RRTConnect", time_budget=PLAN_BUDGET, seed=i)
        self.ledger.track("plan", send_request(self.planning.plan_client, request).future, PLAN_BUDGET)

    def goal(self, i: int) -> None:
        from maru_planner.ros.planning_client import plan_goal

        goal = plan_goal(
            dict(PAPER_START, r_arm_j4=PAPER_START["r_arm_j4"] + 0.3), start=PAPER_START, planner_id="RRTConnect",
            time_budget=PLAN_BUDGET, seed=i,
        )  # fmt: skip
        sent = self.planning.plan_action_client.send_goal_async(goal)
        self.ledger.track("goal_response", sent, PLAN_BUDGET)
        sent.add_done_callback(lambda future: self._accepted(future, cancel=i % 2 == 0))

    def _accepted(self, future, cancel: bool) -> None:
        handle = future.result()
        self.ledger.track("goal", handle.get_result_async(), PLAN_BUDGET)
        if cancel:
            handle.cancel_goal_async()

    def scene(self, i: int) -> None:
        from maru_planner.ros.planning_client import obstacle_msg
        from maru_planner_interfaces.msg import SceneObstacle
        from maru_planner_interfaces.srv import ApplyScene

        pose = np.eye(4)
        pose[:3, 3] = [0.7, 0.6, 0.3 + 0.01 * (i % 10)]
        if self._hostile():
            message = obstacle_msg("soak_box", "box", [0.1, 0.1, 0.1], pose)
            message.shape.dimensions = [math.inf, 0.1, 0.1]
            self.ledger.count("hostile")
        elif i % 3 == 2:
            message = SceneObstacle(name="soak_box", operation=SceneObstacle.REMOVE)
        else:
            message = obstacle_msg("soak_box", "box", [0.1, 0.1, 0.1], pose)
        future = self.planning.apply_client.call_async(ApplyScene.Request(obstacles=[message]))
        self.ledger.track("scene", future, 10.0)

    def scan(self, i: int) -> None:
        from maru_planner.reactive import LaserScanData
        from maru_planner.ros import reactive_conversions as conv

        stamp = self._now()
        ranges = np.full(361, 8.0)
        ranges[170:190] = 1.5  # an obstacle ahead, slightly left and right
        scan = conv.scan_msg(LaserScanData(-math.pi / 2, math.pi / 360, ranges, 0.05, 10.0, stamp=stamp), "laser_link")
        if self._hostile():
            self.ledger.count("hostile")
            if i % 2:
                self.plan_pub.publish(self.oversized_plan)
            else:
                scan.ranges = [1.0] * 100  # fewer ranges than the angles say
        self.odom_pub.publish(conv.odom_msg((0.0, 0.0, 0.0), 0.0, 0.0, stamp, "odom", "base_link"))
        self.scan_pub.publish(scan)

    def base_plan(self, i: int) -> None:
        from maru_planner.ros.reactive_conversions import pose_stamped_msg
        from maru_planner_interfaces.srv import PlanBasePath

        goal = (500.0, 2.0, 0.0) if self._hostile() else (5.0, 2.0, 0.0)
        request = PlanBasePath.Request(allowed_planning_time=BASE_BUDGET)
        request.start, request.goal = pose_stamped_msg((1.0, 2.0, 0.0), "map", 0.0), pose_stamped_msg(goal, "map", 0.0)
        self.ledger.track("base_plan", self.base_client.call_async(request), BASE_BUDGET)

    def trigger(self, i: int) -> None:
        self.ledger.track("trigger", self.trigger_client.call_async(self.trigger_client.srv_type.Request()), 5.0)


def run(duration: float, logs_dir: str | None = None) -> dict:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    logs = tempfile.TemporaryDirectory(prefix="soak_")
    folder = Path(logs_dir or logs.name)
    folder.mkdir(parents=True, exist_ok=True)
    files = {name: open(folder / f"{name}.log", "w") for name in [*NODES, "trigger"]}
    procs = {
        name: start_python(["-m", module, "--ros-args", "--params-file", str(config_path(config))], files[name])
        for name, (module, config) in NODES.items()
    }
    procs["trigger"] = start_python(["-c", TRIGGER_SERVER], files["trigger"])
    rclpy.init()
    node = rclpy.create_node("soak_client")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    ledger = Ledger()
    crashed: dict[str, float] = {}
    try:
        traffic = Traffic(node, ledger)
        log("waiting for the nodes ...")
        traffic.connect()
        ledger.t0 = time.monotonic()
        log(f"soaking for {duration:.0f} s")
        schedule = {kind: 0.0 for kind in PERIODS}
        sent = dict.fromkeys(PERIODS, 0)
        next_sample, next_report = 0.0, REPORT_PERIOD_S
        while (now := time.monotonic() - ledger.t0) < duration:
            for kind, due in schedule.items():
                if now >= due:
                    getattr(traffic, kind)(sent[kind])
                    sent[kind] += 1
                    schedule[kind] = due + PERIODS[kind]
            if now >= next_sample:
                for name, proc in procs.items():
                    if proc.poll() is not None:
                        crashed.setdefault(name, now)
                    elif name in NODES:
                        ledger.rss.setdefault(name, []).append((now, rss_mb(proc.pid, name == "planning_node")))
                next_sample = now + 1.0
            if now >= next_report:
                report_progress(now, duration, sent, ledger)
                next_report += REPORT_PERIOD_S
            time.sleep(max(0.0, min(schedule.values()) - (time.monotonic() - ledger.t0)))
        log("draining the answers ...")
        drain_until = time.monotonic() + max(PLAN_BUDGET, BASE_BUDGET) + ANSWER_GRACE_S
        while time.monotonic() < drain_until and ledger.unanswered():
            time.sleep(0.2)
        end = time.monotonic() - ledger.t0
        lost = ledger.unanswered()  # each waited at least its budget + ANSWER_GRACE_S
        crashed.update({name: end for name, proc in procs.items() if proc.poll() is not None and name not in crashed})
        tails = {name: Path(f.name).read_text(errors="replace")[-3000:] for name, f in files.items()}
    finally:
        executor.shutdown(timeout_sec=2.0)
        node.destroy_node()
        rclpy.shutdown()
        for proc in procs.values():
            proc.terminate()
        for proc in procs.values():
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
        for f in files.values():
            f.close()
        logs.cleanup()
    return results_of(ledger, duration, sent, lost, crashed, tails)


def _p99(rows: np.ndarray, start: float, stop: float) -> float:
    window = rows[(rows[:, 0] >= start) & (rows[:, 0] < stop), 1] if len(rows) else np.zeros(0)
    return float(np.percentile(window, 99)) if len(window) else math.nan


def results_of(ledger: Ledger, duration: float, sent: dict, lost: dict, crashed: dict, tails: dict) -> dict:
    warm_up, window = min(WARM_UP_S, duration / 6.0), min(WINDOW_S, duration / 3.0)
    growth = {}
    for name, samples in ledger.rss.items():
        rows = np.array(samples)
        base = rows[rows[:, 0] >= warm_up, 1]
        growth[name] = float((base[-1] - base[0]) / base[0]) if len(base) >= 2 else math.nan
    drift = {}
    for kind in ("plan", "trigger"):
        rows = ledger.latencies(kind)
        first, last = _p99(rows, 0.0, window), _p99(rows, duration - window, duration)
        drift[kind] = {"p99_first_ms": first * 1e3, "p99_last_ms": last * 1e3, "drift": last / first - 1.0}
    summary = {
        "duration_s": duration,
        "rss_growth": max(growth.values()) if growth else math.nan,
        "crashes": len(crashed),
        "lost": sum(lost.values()),
        "p99_drift": drift["plan"]["drift"],
        "trigger_p99_drift (peer)": drift["trigger"]["drift"],
    }
    summary["met"] = {
        "rss_growth": bool(summary["rss_growth"] <= TARGETS["rss_growth"]),
        "crashes": summary["crashes"] == 0,
        "lost": summary["lost"] == 0,
        "p99_drift": bool(abs(summary["p99_drift"]) <= TARGETS["p99_drift"]),
    }
    return {
        "summary": summary,
        "targets": TARGETS,
        "warm_up_s": warm_up,
        "window_s": window,
        "sent": sent,
        "hostile": ledger.counts.get("hostile", 0),
        "lost_by_kind": lost,
        "crashed": crashed,
        "rss_growth_by_node": growth,
        "p99": drift,
        "rss_mb": {name: samples for name, samples in ledger.rss.items()},
        "latency_s": {kind: ledger.latencies(kind).tolist() for kind in ("plan", "goal", "base_plan", "trigger")},
        "log_tails_of_crashed": {name: tails[name] for name in crashed},
    }


def table(results: dict) -> str:
    s = results["summary"]
    lines = [
        f"# Soak: three nodes, mixed traffic, {s['duration_s']:.0f} s",
        "",
        f"Sent: {results['sent']}; {results['hostile']} of them hostile. Warm-up {results['warm_up_s']:.0f} s, "
        f"p99 windows {results['window_s']:.0f} s. Baseline peer: an empty rclpy Trigger service in its own process.",
        "",
        "| measure | value | target | met |",
        "|---|---|---|---|",
        f"| rss_growth (largest node) | {s['rss_growth']:.2%} | <= 5 % | {s['met']['rss_growth']} |",
        f"| crashes | {s['crashes']} | 0 | {s['met']['crashes']} |",
        f"| lost | {s['lost']} | 0 | {s['met']['lost']} |",
        f"| p99_drift (plan_motion) | {s['p99_drift']:+.1%} | within 20 % | {s['met']['p99_drift']} |",
        f"| p99 drift of the Trigger peer | {s['trigger_p99_drift (peer)']:+.1%} | | |",
        "",
        "| node | RSS first MB | RSS last MB | growth after warm-up |",
        "|---|---|---|---|",
    ]
    for name, samples in results["rss_mb"].items():
        growth = results["rss_growth_by_node"][name]
        lines.append(f"| {name} | {samples[0][1]:.0f} | {samples[-1][1]:.0f} | {growth:+.2%} |")
    lines += ["", "| latency | p99 first window ms | p99 last window ms |", "|---|---|---|"]
    for kind, row in results["p99"].items():
        lines.append(f"| {kind} | {row['p99_first_ms']:.1f} | {row['p99_last_ms']:.1f} |")
    if results["lost_by_kind"] or results["crashed"]:
        lines += ["", f"Lost by kind: {results['lost_by_kind']}; crashed: {results['crashed']}"]
    return "\n".join(lines) + "\n"


def plot(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    for name, samples in results["rss_mb"].items():
        rows = np.array(samples)
        top.plot(rows[:, 0], rows[:, 1], label=name)
    top.axvline(results["warm_up_s"], color="grey", linestyle=":", label="end of warm-up")
    top.set_ylabel("RSS (MB)")
    top.legend(fontsize=8)
    for kind in ("plan", "goal", "base_plan", "trigger"):
        rows = np.array(results["latency_s"][kind]).reshape(-1, 2)
        if len(rows):
            bottom.plot(rows[:, 0], rows[:, 1] * 1e3, ".", markersize=2, label=kind)
    bottom.set_yscale("log")
    bottom.set_ylabel("latency (ms)")
    bottom.set_xlabel("time (s)")
    bottom.legend(fontsize=8)
    s = results["summary"]
    top.set_title(
        f"soak {s['duration_s']:.0f} s: RSS growth {s['rss_growth']:.1%}, lost {s['lost']}, crashes {s['crashes']}, "
        f"p99 drift {s['p99_drift']:+.0%}"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--duration", type=float, default=FULL_DURATION_S,
        help=f"seconds of traffic (the issue's: {FULL_DURATION_S:.0f}; shorter runs write under bench/results/quick/)",
    )  # fmt: skip
    parser.add_argument("--quick", action="store_true", help="60 s, written under bench/results/quick/")
    parser.add_argument("--logs", help="keep the nodes' logs in this folder (default: deleted)")
    parser.add_argument("--out", type=Path, help="write soak.{json,md,png} into this folder instead")
    args = parser.parse_args(argv)
    if not args.duration > 0:
        parser.error("--duration must be > 0")
    configure_loopback_dds(random_domain=True)
    duration = 60.0 if args.quick else args.duration
    results = run(duration, args.logs)
    scratch = duration < FULL_DURATION_S  # only a full run replaces the committed results
    out = args.out / NAME if args.out else RESULTS / NAME
    write_results(out, results, table(results), lambda path: plot(results, path), quick=scratch and not args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
