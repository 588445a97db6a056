"""The carry demo through the nodes (``python -m maru_planner.execution.carry_demo --through-ros``).

    python -m maru_planner.ros.carry_demo_run --json OUT.json [--seed 1] [--real-time-factor 1] [--logs DIR]

Processes: ``arm_sim_node`` (MuJoCo, the box attached to ``r_hand`` and weighing ``BOX_MASS``, the arm started at
the carry's start pose: parameters ``initial_joint_names``/``initial_positions``, ``payload_names``/
``payload_masses``) and ``planning_node`` (the same scene), both given
:func:`~maru_planner.execution.carry_demo.through_ros_scene` as their scene file. This process sends one
``plan_motion`` goal with ``execute: true``: the in-process carry (:func:`~maru_planner.execution.carry_demo.
carry_problem`, the dual-arm lift-and-tilt while the waist turns the box from the right of the desk to the left)
from the carry's start, with the hands' relative pose (``l_hand`` in ``r_hand``'s frame, as at the start) held
to 1 mm / 0.01 rad by ``path_constraints``' relative fields. While it executes this process records /joint_states
and arm_sim_node's ``execute_trajectory`` feedback (the controller's desired and actual samples); everything goes
to ``--json`` for the demo to measure and draw. The DDS traffic stays on loopback, in the user's exported
ROS_DOMAIN_ID or a random one. Progress on stderr; a failure is one line on stderr and exit code 1.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import rclpy
from geometry_msgs.msg import Pose, Quaternion
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from sensor_msgs.msg import JointState

from maru_planner.cli_parser import OneLineParser
from maru_planner.errors import one_line
from maru_planner.execution.carry_demo import BOX, BOX_MASS, carry_problem, through_ros_scene
from maru_planner.paths import config_path
from maru_planner.robot import RobotModel
from maru_planner.ros.env import configure_loopback_dds, unused_domain_id
from maru_planner.ros.node_processes import NodeProcesses
from maru_planner.ros.planning_client import PlanningClient, plan_goal, send_plan_goal, status_name
from maru_planner_interfaces.action import ExecuteTrajectory
from maru_planner_interfaces.msg import PathConstraints

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


def progress(message: str) -> None:
    print(f"[carry_demo_run] {message}", file=sys.stderr, flush=True)


def check_alive(nodes: NodeProcesses) -> None:
    """RunFailed naming a node that exited, with its log's last line."""
    dead = nodes.dead()
    if dead is not None:
        raise RunFailed(f"{dead} exited ({nodes.procs[dead].returncode}): {nodes.last_line(dead)}")


def start_nodes(nodes: NodeProcesses, scene_file: Path, real_time_factor: float, start: dict[str, float]) -> None:
    scene = ["-p", f"scene_file:={scene_file}"]
    arm_yaml, planner_yaml = str(config_path("arm_sim.yaml")), str(config_path("planner.yaml"))
    arm = [
        "-p", f"real_time_factor:={real_time_factor}",
        "-p", f"initial_joint_names:=[{', '.join(start)}]",
        "-p", f"initial_positions:=[{', '.join(repr(float(v)) for v in start.values())}]",
        "-p", f"payload_names:=[{BOX}]", "-p", f"payload_masses:=[{float(BOX_MASS)!r}]",
    ]  # fmt: skip
    nodes.start("arm_sim_node", ["--ros-args", "--params-file", arm_yaml, *scene, *arm])
    nodes.start("planning_node", ["--ros-args", "--params-file", planner_yaml, *scene, "-p", "workers:=1"])


def carry_constraints() -> PathConstraints:
    """The carry's path constraint as a message: ``l_hand`` in ``r_hand``'s frame held as at the request's start
    (an all-zero quaternion in ``relative_pose``: the node takes the pose from the start state)."""
    held = carry_problem().constraints(RobotModel.maru1()).relative
    assert held is not None
    as_at_start = Pose(orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=0.0))
    return PathConstraints(
        relative_link_a=held.link_a, relative_link_b=held.link_b, relative_pose=as_at_start,
        relative_position_tolerance=held.position_tolerance, relative_orientation_tolerance=held.orientation_tolerance,
    )  # fmt: skip


def execute(client: PlanningClient, nodes: NodeProcesses, start: dict[str, float], goal: dict[str, float], seed: int,
            what: str) -> tuple[int, Any]:  # fmt: skip
    """Plan from ``start`` to ``goal`` keeping :func:`carry_constraints` and execute it: (goal status, result), or
    RunFailed."""
    request = plan_goal(goal, start=start, execute=True, seed=seed, time_budget=PLAN_BUDGET, group="upper_body")
    request.path_constraints = carry_constraints()
    handle = send_plan_goal(client.plan_action_client, request)
    deadline = time.monotonic() + PLAN_BUDGET + 120.0
    while not handle.done:
        check_alive(nodes)
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
    """Start the nodes (the arm at the carry's start), carry; the recorded run as a JSON-ready dict."""
    scene_file = log_dir / "carry_scene.yaml"
    scene_file.write_text(through_ros_scene().to_yaml())
    problem = carry_problem()
    names = RobotModel.maru1().groups[problem.group]
    start = dict(zip(names, problem.start, strict=True))
    carry = dict(zip(names, problem.goal, strict=True))
    nodes = NodeProcesses(log_dir)
    rclpy.init()
    node = rclpy.create_node("carry_demo_run")
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    try:
        recorder = Recorder(node)
        client = PlanningClient(node=node)
        spinner.start()
        start_nodes(nodes, scene_file, real_time_factor, start)
        progress(f"nodes started (ROS_DOMAIN_ID {os.environ.get('ROS_DOMAIN_ID')}, logs {log_dir})")
        if not client.plan_client.wait_for_service(timeout_sec=NODE_TIMEOUT):
            check_alive(nodes)
            raise RunFailed(f"planning_node served no plan_motion within {NODE_TIMEOUT:.0f} s")
        client.wait_until_ready(timeout=NODE_TIMEOUT)  # both directions proven before the first goal
        if not recorder.seen_state.wait(NODE_TIMEOUT):
            raise RunFailed(f"arm_sim_node published no joint_states within {NODE_TIMEOUT:.0f} s")
        progress("carry: plan_motion (relative pose held), execute")
        recorder.on = True
        status, result = execute(client, nodes, start, carry, seed, "carry")
        time.sleep(0.2)  # the last samples in flight
        recorder.on = False
        progress(f"carry executed ({result.execution_time:.2f} s)")
        header = {"goal_status": status_name(status), "real_time_factor": real_time_factor}
        return {**header, **record(result, recorder)}
    finally:
        nodes.stop()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


def record(result: Any, recorder: Recorder) -> dict[str, Any]:
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
