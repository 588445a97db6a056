"""The carry demo through the nodes (``python -m maru_planner.execution.carry_demo --through-ros``).

    python -m maru_planner.ros.carry_demo_run --json OUT.json [--seed 1] [--real-time-factor 1] [--logs DIR]

Processes: ``arm_sim_node`` (MuJoCo, the box attached to ``r_hand``) and ``planning_node`` (the same scene), both
given :func:`~maru_planner.execution.carry_demo.through_ros_scene` as their scene file. This process sends two
``plan_motion`` goals with ``execute: true``, the start of each the arm's /joint_states: the approach (home to the
carry's start) and the carry (the waist turns the box from the right of the desk to the left, both hands holding
it). While the carry executes it records /joint_states and arm_sim_node's ``execute_trajectory`` feedback (the
controller's desired and actual samples); everything goes to ``--json`` for the demo to measure and draw. The DDS
traffic stays on loopback, in the user's exported ROS_DOMAIN_ID or a random one. Progress on stderr; a failure is one
line on stderr and exit code 1.
"""

from __future__ import annotations

import json
import os
import random
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import rclpy
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from sensor_msgs.msg import JointState

from maru_planner.cli_parser import OneLineParser
from maru_planner.errors import one_line
from maru_planner.execution.carry_demo import carry_goals, through_ros_scene
from maru_planner.paths import config_path
from maru_planner.ros.env import configure_loopback_dds
from maru_planner.ros.planning_client import PlanningClient, status_name
from maru_planner_interfaces.action import ExecuteTrajectory

SUCCEEDED = 4  # action_msgs/GoalStatus
PLAN_BUDGET = 20.0  # s per plan
NODE_TIMEOUT = 120.0  # s for both nodes to serve (a loaded machine)


class RunFailed(Exception):
    """The graph could not carry the run out: a node died, a goal failed, a timeout."""


class Recorder:
    """/joint_states and execute_trajectory feedback while :attr:`on`, with their header stamps (s)."""

    def __init__(self, node: Node):
        self.on = False
        self.lock = threading.Lock()
        self.states: list[tuple[float, list[str], list[float]]] = []
        self.feedback: list[tuple[float, list[str], list[float], list[float]]] = []
        self.seen_state = threading.Event()
        node.create_subscription(JointState, "joint_states", self._on_state, 100)
        feedback = ExecuteTrajectory.Impl.FeedbackMessage
        node.create_subscription(feedback, "execute_trajectory/_action/feedback", self._on_feedback, 100)

    def _on_state(self, msg: JointState) -> None:
        self.seen_state.set()
        if self.on:
            with self.lock:
                self.states.append((_stamp(msg.header.stamp), list(msg.name), list(msg.position)))

    def _on_feedback(self, msg: Any) -> None:
        f = msg.feedback
        if self.on:
            with self.lock:
                self.feedback.append(
                    (_stamp(f.header.stamp), list(f.joint_names), list(f.desired.positions), list(f.actual.positions))
                )


def _stamp(stamp: Any) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


class Nodes:
    """arm_sim_node and planning_node as processes, their logs under ``log_dir``."""

    def __init__(self, log_dir: Path):
        self.log_dir = log_dir
        self.procs: dict[str, subprocess.Popen] = {}

    def start(self, name: str, args: list[str]) -> None:
        log = open(self.log_dir / f"{name}.log", "w")  # noqa: SIM115 -- the child writes it until stop()
        self.procs[name] = subprocess.Popen(
            [sys.executable, "-m", f"maru_planner.ros.{name}", "--ros-args", *args], stdout=log,
            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=dict(os.environ),
        )  # fmt: skip

    def check_alive(self) -> None:
        for name, proc in self.procs.items():
            if proc.poll() is not None:
                lines = (self.log_dir / f"{name}.log").read_text(errors="replace").strip().splitlines()
                raise RunFailed(f"{name} exited ({proc.returncode}): {lines[-1] if lines else 'no output'}")

    def stop(self) -> None:
        for proc in self.procs.values():
            if proc.poll() is None:
                proc.terminate()
        for proc in self.procs.values():
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)


def unused_domain_id() -> int:
    """A random ROS domain id in 1..100 whose Fast DDS discovery ports no participant on this machine holds (RTPS
    port mapping: participant ``i`` of domain ``d`` takes UDP 7410 + 250 d + 2 i); any one if all are taken."""
    domains = list(range(1, 101))
    random.SystemRandom().shuffle(domains)
    return next((d for d in domains if not any(_port_taken(7410 + 250 * d + 2 * i) for i in range(4))), domains[0])


def _port_taken(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return True
    return False


def progress(message: str) -> None:
    print(f"[carry_demo_run] {message}", file=sys.stderr, flush=True)


def start_nodes(nodes: Nodes, scene_file: Path, real_time_factor: float) -> None:
    scene = ["-p", f"scene_file:={scene_file}"]
    arm_yaml, planner_yaml = str(config_path("arm_sim.yaml")), str(config_path("planner.yaml"))
    nodes.start("arm_sim_node", ["--params-file", arm_yaml, *scene, "-p", f"real_time_factor:={real_time_factor}"])
    nodes.start("planning_node", ["--params-file", planner_yaml, *scene, "-p", "workers:=1"])


def execute(client: PlanningClient, nodes: Nodes, goal: dict[str, float], seed: int, what: str) -> tuple[int, Any]:
    """Plan to ``goal`` from the arm's /joint_states and execute it: (goal status, result), or RunFailed."""
    handle = client.plan_action(goal, execute=True, seed=seed, time_budget=PLAN_BUDGET, group="upper_body")
    deadline = time.monotonic() + PLAN_BUDGET + 120.0
    while not handle.done:
        nodes.check_alive()
        if time.monotonic() > deadline:
            raise RunFailed(f"{what}: no plan_motion result within {PLAN_BUDGET + 120.0:.0f} s")
        time.sleep(0.05)
    status, result = handle.result(timeout=10.0)
    if status != SUCCEEDED or result.execution_error_code != 0:
        raise RunFailed(
            f"{what}: {status_name(status)}: plan {result.error.code} {result.error.message}; "
            f"execution {result.execution_error_code} {result.execution_error_string}"
        )
    return status, result


def run(seed: int, real_time_factor: float, log_dir: Path) -> dict[str, Any]:
    """Start the nodes, approach, carry; the recorded run as a JSON-ready dict."""
    scene_file = log_dir / "carry_scene.yaml"
    scene_file.write_text(through_ros_scene().to_yaml())
    approach, carry = carry_goals()
    nodes = Nodes(log_dir)
    rclpy.init()
    node = rclpy.create_node("carry_demo_run")
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    try:
        recorder = Recorder(node)
        client = PlanningClient(node=node)
        spinner.start()
        start_nodes(nodes, scene_file, real_time_factor)
        progress(f"nodes started (ROS_DOMAIN_ID {os.environ.get('ROS_DOMAIN_ID')}, logs {log_dir})")
        if not client.plan_client.wait_for_service(timeout_sec=NODE_TIMEOUT):
            nodes.check_alive()
            raise RunFailed(f"planning_node served no plan_motion within {NODE_TIMEOUT:.0f} s")
        client.wait_until_ready(timeout=NODE_TIMEOUT)  # both directions proven before the first goal
        if not recorder.seen_state.wait(NODE_TIMEOUT):
            raise RunFailed(f"arm_sim_node published no joint_states within {NODE_TIMEOUT:.0f} s")
        progress("approach: home -> the carry's start (plan_motion, execute)")
        _, first = execute(client, nodes, approach, seed, "approach")
        progress(f"approach executed ({first.execution_time:.2f} s); carry (plan_motion, execute)")
        recorder.on = True
        status, result = execute(client, nodes, carry, seed, "carry")
        time.sleep(0.2)  # the last samples in flight
        recorder.on = False
        progress(f"carry executed ({result.execution_time:.2f} s)")
        header = {"goal_status": status_name(status), "real_time_factor": real_time_factor}
        return {**header, **record(result, recorder, first.execution_time)}
    finally:
        nodes.stop()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


def record(result: Any, recorder: Recorder, approach_time: float) -> dict[str, Any]:
    points = result.trajectory.points
    with recorder.lock:
        states, feedback = list(recorder.states), list(recorder.feedback)
    return {
        "joint_names": list(result.trajectory.joint_names),
        "plan": {
            "times": [_stamp(p.time_from_start) for p in points],
            "positions": [list(p.positions) for p in points],
            "velocities": [list(p.velocities) for p in points],
            "accelerations": [list(p.accelerations) for p in points],
            "planner": result.stats.planner_id,
            "waypoints": int(result.stats.waypoints),
            "certified": bool(result.stats.certified),
        },
        "execution": {
            "code": int(result.execution_error_code),
            "message": result.execution_error_string,
            "tracking_error": float(result.execution_tracking_error),
            "time": float(result.execution_time),
            "approach_time": float(approach_time),
        },
        "joint_states": [{"stamp": s, "names": n, "positions": p} for s, n, p in states],
        "feedback": [{"stamp": s, "names": n, "desired": d, "actual": a} for s, n, d, a in feedback],
    }


def main(argv: list[str] | None = None) -> int:
    parser = OneLineParser(prog="carry_demo_run", description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True, help="write the recorded run here")
    parser.add_argument("--seed", type=int, default=1, help="the planner's seed")
    parser.add_argument("--real-time-factor", type=float, default=1.0, help="arm_sim_node's real_time_factor")
    parser.add_argument("--logs", type=Path, help="the nodes' logs (default: a scratch directory)")
    args = parser.parse_args(argv)
    exported = os.environ.get("ROS_DOMAIN_ID", "")
    configure_loopback_dds(int(exported) if exported.isdigit() else unused_domain_id())
    try:
        with tempfile.TemporaryDirectory(prefix="maru_carry_") as scratch:
            log_dir = args.logs or Path(scratch)
            log_dir.mkdir(parents=True, exist_ok=True)
            payload = run(args.seed, args.real_time_factor, log_dir)
        args.json.write_text(json.dumps(payload) + "\n")
    except (RunFailed, TimeoutError, OSError) as exc:
        print(f"carry through ROS failed: {one_line(str(exc))}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("carry through ROS interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
