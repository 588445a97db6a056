"""One BARN run through ROS (``maru-barn --through-ros``): every node its own process, lock-step over topics.

    python -m maru_planner.ros.barn_ros_run --world 0 --seed 0 --json out.json [--logs DIR]

Processes: ``mujoco_sim_node`` (the world, lock-step: one control period per ``cmd_vel``), ``base_planner_node``
(our cost-aware A* on the map this process publishes; it publishes its path on ``plan``) and ``reactive_node``
(unchanged, ``use_sim_time``, its ``cmd_vel`` renamed ``cmd_vel_strip``); this process is the rest of the
in-process stack (:class:`~maru_planner.barn.stack.BarnStack`): the map built from ``scan`` and ``odom``,
re-planning every ``replan_period`` through ``plan_base_path``, the recovery and the footprint check on the
strip's twist (``reactive_node/cmd_vel_stamped``, stamped with the scan it answers), then ``cmd_vel``. The sim's
``~/status`` (ground truth) is read only to score the run. Each run gets its own DDS domain.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np
import rclpy
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String

from maru_planner.barn.scoring import RunJudge, RunScore, barn_metric
from maru_planner.barn.stack import BarnStack, RunTrace, StackConfig, strip_params, to_odom, to_world
from maru_planner.paths import config_path
from maru_planner.physics.barn_world import GOAL, START
from maru_planner.physics.jackal import JackalSpec
from maru_planner.physics.laser import LaserSpec, Scan
from maru_planner.ros import base_conversions, reactive_conversions
from maru_planner.ros.env import configure_loopback_dds, unused_domain_id
from maru_planner.ros.node_processes import NodeProcesses
from maru_planner_interfaces.srv import PlanBasePath

RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
# the sim's first state waits for these: scan and odom (reactive_node and this process), ~/status (this process)
FIRST_STATE_SUBSCRIBERS = 5
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)

USER_DOMAIN = os.environ.get("ROS_DOMAIN_ID", "")  # read at import, before a run sets its own


def _param(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(_param(v) for v in value) + "]"
    return repr(float(value)) if isinstance(value, float) else str(value)


def reactive_arguments(config: StackConfig, laser: LaserSpec) -> list[str]:
    """reactive_node's parameters: the in-process stack's strip, sim time, reliable scans, no arms."""
    strip = strip_params(config, laser.x)
    args = ["--ros-args", "--params-file", str(config_path("reactive.yaml")), "-r", "cmd_vel:=cmd_vel_strip"]
    for item in fields(strip):
        value = getattr(strip, item.name)
        if item.name == "beam_window" and value is None:
            value = (0, laser.beams - 1)  # every beam
        if value is not None:
            args += ["-p", f"{item.name}:={_param(value)}"]
    overrides = {"use_sim_time": True, "scan_reliability": "reliable", "publish_arm": False, "scan_timeout": 30.0}
    overrides |= {"stale_scan_timeout": 30.0, "future_tolerance": 30.0}  # lock-step: wall time means nothing
    return args + [arg for name, value in overrides.items() for arg in ("-p", f"{name}:={_param(value)}")]


def base_planner_arguments(config: StackConfig) -> list[str]:
    """base_planner_node as the in-process planner: astar, a disc of plan_radius (the square's circumradius)."""
    half = config.plan_radius / math.sqrt(2.0)
    square = [half, half, -half, half, -half, -half, half, -half]
    values = {
        "planner_id": "astar", "footprint": square, "inflation_radius": config.inflation_radius,
        "cost_scaling_factor": config.cost_scaling_factor, "astar.cost_travel_multiplier":
        config.cost_travel_multiplier, "allowed_planning_time": 1.0, "unknown_is_occupied": False,
    }  # fmt: skip
    args = ["--ros-args", "--params-file", str(config_path("base_planner.yaml"))]
    return args + [arg for name, value in values.items() for arg in ("-p", f"{name}:={_param(value)}")]


class _Step:
    """What arrives for one control period: the scan, the odometry, the sim's status, the strip's twist."""

    def __init__(self) -> None:
        self.scan: Scan | None = None
        self.odom: np.ndarray | None = None
        self.status: dict | None = None
        self.strip: tuple[float, float] | None = None

    def ready(self) -> bool:
        return all(part is not None for part in (self.scan, self.odom, self.status, self.strip))


def _key(stamp: Any) -> int:
    return round(reactive_conversions.stamp_to_s(stamp) * 1000)


class StackNode:
    """This process's part of the stack, on a plain rclpy node."""

    def __init__(self, node: Node, config: StackConfig, jackal: JackalSpec, laser: LaserSpec):
        self.node, self.config = node, config
        self.stack = BarnStack(config, to_odom(START, GOAL), laser.x, (jackal.chassis_length / 2,
                                                                        jackal.chassis_width / 2))  # fmt: skip
        self.judge = RunJudge(START[:2], GOAL, config.time_limit, config.max_wait)
        self.steps: dict[int, _Step] = {}
        self.done_keys: set[int] = set()
        self.trajectory: list[tuple[float, float, float]] = [START]
        self.min_clearance = math.inf
        self.last_status: dict | None = None
        self.contacts: list[tuple[float, float, float]] = []
        self.planning = False
        self.cmd_pub = node.create_publisher(Twist, "cmd_vel", RELIABLE)
        self.goal_pub = node.create_publisher(PoseStamped, "goal_pose", LATCHED)
        self.map_pub = node.create_publisher(OccupancyGridMsg, "map", LATCHED)
        self.plan_client = node.create_client(PlanBasePath, "plan_base_path")
        node.create_subscription(LaserScan, "scan", self._on_scan, RELIABLE)
        node.create_subscription(Odometry, "odom", self._on_odom, RELIABLE)
        node.create_subscription(TwistStamped, "reactive_node/cmd_vel_stamped", self._on_strip, RELIABLE)

    def listen_to_status(self) -> None:
        """Subscribe to the sim's ``~/status``: the last of the subscriptions the sim's first state waits for."""
        self.node.create_subscription(String, "mujoco_sim_node/status", self._on_status, QoSProfile(depth=50))

    def publish_goal(self) -> None:
        goal = self.stack.goal
        self.goal_pub.publish(reactive_conversions.pose_stamped_msg((float(goal[0]), float(goal[1]), 0.0), "odom", 0.0))

    # ------------------------------------------------------------------------------------------ inputs --
    def _step(self, stamp: Any) -> tuple[int, _Step]:
        key = _key(stamp)
        return key, self.steps.setdefault(key, _Step())

    def _on_scan(self, msg: LaserScan) -> None:
        key, step = self._step(msg.header.stamp)
        data = reactive_conversions.scan_from_msg(msg)
        step.scan = Scan(np.asarray(data.ranges), data.angle_min, data.angle_increment, data.range_min,
                         data.range_max, data.stamp)  # fmt: skip
        self._try(key)

    def _on_odom(self, msg: Odometry) -> None:
        key, step = self._step(msg.header.stamp)
        step.odom = np.array(reactive_conversions.pose_from_odom(msg), dtype=float)
        self._try(key)

    def _on_status(self, msg: String) -> None:
        status = json.loads(msg.data)
        key = round(status["time"] * 1000)
        self.steps.setdefault(key, _Step()).status = status
        self._try(key)

    def _on_strip(self, msg: TwistStamped) -> None:
        key, step = self._step(msg.header.stamp)
        step.strip = (float(msg.twist.linear.x), float(msg.twist.angular.z))
        self._try(key)

    # ------------------------------------------------------------------------------------------- a step --
    def _try(self, key: int) -> None:
        step = self.steps.get(key)
        if step is None or not step.ready() or key in self.done_keys or self.judge.outcome is not None:
            return
        self.done_keys.add(key)
        del self.steps[key]
        assert step.status is not None and step.odom is not None and step.scan is not None and step.strip
        status, now = step.status, step.status["time"]
        self.last_status = status
        x, y, yaw = status["truth"]
        self.trajectory.append((x, y, yaw))
        if status["clearance"] is not None:
            self.min_clearance = min(self.min_clearance, status["clearance"])
        if status["first_contact"] is not None and not self.contacts:
            self.contacts.append(tuple(status["first_contact"]))
        if self.judge.update(now, x, y, status["collided"]) is not None:
            return
        override, body_points = self.stack.observe(now, step.odom, step.scan)
        command = override if override is not None else self.stack.guard(*step.strip, body_points)
        if override is None and self.stack.replan_due(now):
            self._replan(step.odom, command, now, retry=True)
        else:
            self._command(command, now)

    def _replan(self, odom: np.ndarray, command: tuple[float, float], now: float, retry: bool) -> None:
        """The map to base_planner_node, then plan_base_path; the command goes out once the path is in."""
        grid = self.stack.map.grid()
        stamp = reactive_conversions.s_to_stamp(now)
        self.map_pub.publish(base_conversions.grid_to_msg(grid, grid.occupied, stamp, "odom"))
        request = PlanBasePath.Request()
        request.start = reactive_conversions.pose_stamped_msg(
            (float(odom[0]), float(odom[1]), float(odom[2])), "odom", now
        )
        goal = self.stack.goal
        request.goal = reactive_conversions.pose_stamped_msg((float(goal[0]), float(goal[1]), 0.0), "odom", now)
        request.planner_id = "astar"
        future = self.plan_client.call_async(request)
        future.add_done_callback(lambda done: self._planned(done.result(), odom, command, now, retry))

    def _planned(self, response: Any, odom: np.ndarray, command: tuple[float, float], now: float, retry: bool) -> None:
        self.stack.replans += 1
        if response is not None and response.error_code == 0 and len(response.path.poses) >= 2:
            self.stack.path = np.array([[p.pose.position.x, p.pose.position.y] for p in response.path.poses])
        elif retry:  # drift or noise may have closed the way: keep only what is seen now
            self.stack.map.clear(keep_near=(float(odom[0]), float(odom[1])))
            self._replan(odom, command, now, retry=False)
            return
        self._command(command, now)

    def _command(self, command: tuple[float, float], now: float) -> None:
        msg = Twist()
        msg.linear.x, msg.angular.z = float(command[0]), float(command[1])
        self.cmd_pub.publish(msg)


def _spin_until(node: Node, predicate: Any, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what} within {timeout} s")
        rclpy.spin_once(node, timeout_sec=0.05)


def _prove_planner(node: Node, client: Any, timeout: float) -> None:
    """A harmless plan_base_path until one is answered: right after discovery the server may not have matched
    our reply reader yet, and rmw_fastrtps drops the reply (a replan would wait for nothing)."""
    deadline, attempt = time.monotonic() + timeout, 1.0
    _spin_until(node, client.service_is_ready, timeout, "base_planner_node never appeared")
    request = PlanBasePath.Request()
    request.start = reactive_conversions.pose_stamped_msg((0.0, 0.0, 0.0), "odom", 0.0)
    request.goal = reactive_conversions.pose_stamped_msg((0.0, 0.0, 0.0), "odom", 0.0)
    request.planner_id = "astar"
    while time.monotonic() < deadline:
        future = client.call_async(request)
        wait_until = min(time.monotonic() + attempt, deadline)
        while not future.done() and time.monotonic() < wait_until:
            rclpy.spin_once(node, timeout_sec=0.05)
        if future.done():
            return
        client.remove_pending_request(future)
        attempt = min(2.0 * attempt, 8.0)
    raise TimeoutError(f"base_planner_node never answered plan_base_path within {timeout} s")


def run_through_ros(
    world: int | None, grid_file: str | None, optimal_time_s: float, seed: int, name: str, log_dir: Path,
    config: StackConfig | None = None, wall_limit: float = 600.0,
) -> tuple[RunScore, RunTrace]:  # fmt: skip
    """One run: start the nodes, hand reactive_node its goal, start the sim, follow it to the outcome."""
    config = config or StackConfig()
    jackal, laser = JackalSpec(), LaserSpec()
    # the user's exported domain, else a free one per run (a run's nodes never meet a previous run's)
    configure_loopback_dds(int(USER_DOMAIN) if USER_DOMAIN.isdigit() else unused_domain_id())
    procs = NodeProcesses(log_dir)
    # all three start at once, before this process sets up (start-up is most of a short run's wall time); the
    # sim holds its first state until reactive_node and this process subscribe, and this process subscribes to
    # its status only once reactive_node has the goal: the first scan never finds reactive_node without one
    source = ["-p", f"grid_file:={grid_file}"] if grid_file else ["-p", f"world:={world}"]
    sim_args = ["--ros-args", "--params-file", str(config_path("mujoco_sim.yaml")), *source]
    held = ["-p", f"first_state_subscribers:={FIRST_STATE_SUBSCRIBERS}", "-p", "lockstep_wait:=10.0"]
    try:
        procs.start("mujoco_sim_node", [*sim_args, "-p", f"seed:={seed}", *held])
        procs.start("base_planner_node", base_planner_arguments(config))
        procs.start("reactive_node", reactive_arguments(config, laser))
        rclpy.init()
        node = rclpy.create_node("barn_stack")
    except BaseException:  # the nodes never outlive this process
        procs.stop()
        raise
    try:
        stack = StackNode(node, config, jackal, laser)
        _spin_until(node, lambda: stack.goal_pub.get_subscription_count() > 0, 60.0, "reactive_node never appeared")
        stack.publish_goal()  # latched: reactive_node has it before the first scan
        _spin_until(node, lambda: "goal (" in procs.log("reactive_node"), 30.0, "reactive_node took no goal")
        _prove_planner(node, stack.plan_client, 60.0)
        stack.listen_to_status()
        wall0, cpu0 = time.perf_counter(), time.process_time()

        def over() -> bool:
            dead = procs.dead()
            if dead is not None:
                raise RuntimeError(f"{dead} died: {procs.last_line(dead)}")
            return stack.judge.outcome is not None

        _spin_until(node, over, wall_limit, "the run did not end")
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    finally:
        node.destroy_node()
        rclpy.shutdown()
        procs.stop()
    status = stack.last_status or {}
    now = float(status.get("time", 0.0))
    elapsed = stack.judge.elapsed(now)
    success = stack.judge.outcome == "goal"
    score = RunScore(
        world=name, seed=seed, success=success, collision=stack.judge.outcome == "collision",
        timeout=stack.judge.outcome == "timeout", time_s=elapsed, optimal_time_s=optimal_time_s,
        metric=barn_metric(success, elapsed, optimal_time_s), min_clearance_m=stack.min_clearance,
        sim_time_s=now, wall_time_s=wall, cpu_time_s=cpu, cmd_timeouts=int(status.get("cmd_timeouts", 0)),
        nan_commands=int(status.get("nan_commands", 0)), replans=stack.stack.replans,
    )  # fmt: skip
    trace = RunTrace(np.array(stack.trajectory), to_world(START, stack.stack.path), stack.contacts)
    return score, trace


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--world", type=int)
    source.add_argument("--grid", help="a checked 30 x 30 .npy grid")
    parser.add_argument("--optimal-time", type=float, required=True, help="OT of the world (s)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--name", default="grid")
    parser.add_argument("--json", required=True, help="write the score and the trace here")
    parser.add_argument("--logs", default=None, help="the nodes' logs (default: beside --json)")
    args = parser.parse_args(argv)
    out = Path(args.json)
    log_dir = Path(args.logs) if args.logs else out.parent / f"{out.stem}_logs"
    log_dir.mkdir(parents=True, exist_ok=True)
    try:
        score, trace = run_through_ros(args.world, args.grid, args.optimal_time, args.seed, args.name, log_dir)
    except (TimeoutError, RuntimeError) as exc:
        print(f"barn_ros_run: {exc} (logs in {log_dir})", file=sys.stderr)
        return 1
    payload = {
        "run": score.to_json(),
        "trajectory": np.round(trace.trajectory, 4).tolist(),
        "global_path": np.round(trace.global_path, 4).tolist(),
        "contacts": [list(c) for c in trace.contacts],
    }
    out.write_text(json.dumps(payload) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
