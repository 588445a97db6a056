"""``make demo``: plan paper 000's 13-DOF Maru-1 problem through the ROS 2 planning service.

Starts ``planning_node`` as its own process (loopback DDS, a random domain id),
calls ``plan_motion`` once per planner with the paper's start and goal, prints a
table (planner, success, time, nodes, collision checks, path length) and writes
``demo_output/demo.{json,md}`` and a picture of the plan, ``demo_output/plan_13dof.png``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from maru_planner.paths import config_path
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.problems import PROBLEMS
from maru_planner.robot import RobotModel
from maru_planner.ros.env import configure_loopback_dds
from maru_planner.scene import Scene
from maru_planner.viz.plans import plot_plan

# the default planner first (PlannerConfig.default_planner; the node plans on its default collision model)
PLANNERS = ("CompiledRRTConnect", "RRTConnect", "GoalBiasedRRT", "RCRRT", "PRM", "RRT")
COLUMNS = ("planner", "success", "time [s]", "round trip [s]", "nodes", "collision checks", "path length [rad]")


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="maru-demo", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="demo_output", help="output directory (default: demo_output)")
    parser.add_argument("--planners", nargs="+", default=list(PLANNERS), help="planner ids to run")
    parser.add_argument("--time", type=float, default=10.0, help="time budget per plan in seconds")
    parser.add_argument("--seed", type=int, default=1, help="planner seed (-1 = random)")
    parser.add_argument(
        "--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: the exported one, else random)"
    )
    return parser.parse_args(argv)


def start_node(out_dir: Path) -> tuple[subprocess.Popen, Path]:
    log_path = out_dir / "planning_node.log"
    log = open(log_path, "w")  # noqa: SIM115 - closed with the process
    cmd = [
        sys.executable,
        "-m",
        "maru_planner.ros.planning_node",
        "--ros-args",
        "--params-file",
        str(config_path("planner.yaml")),
    ]
    return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL), log_path


def run_planners(client, problem, joint_names, planners, time_budget, seed) -> list[dict]:
    from maru_planner_interfaces.msg import PlanningError

    start, goal = problem.start_dict(joint_names), problem.goal_dict(joint_names)
    rows = []
    for planner_id in planners:
        print(f"[demo] planning with {planner_id} (budget {time_budget:.0f} s) ...", flush=True)
        t0 = time.perf_counter()
        response = client.plan(
            goal, start=start, group=problem.group, planner_id=planner_id, time_budget=time_budget, seed=seed
        )
        round_trip = time.perf_counter() - t0
        ok = response.error.code == PlanningError.SUCCESS
        rows.append(
            {
                "planner": planner_id,
                "success": ok,
                "status_code": response.error.code,
                "message": response.error.message,
                "planning_time": response.planning_time,
                "round_trip": round_trip,
                "nodes": response.stats.nodes,
                "collision_checks": response.stats.collision_checks,
                "path_length": response.stats.path_length if ok else None,
                "waypoints": response.stats.waypoints,
                "response": response,
            }
        )
    return rows


def format_table(rows: list[dict]) -> list[str]:
    cells = [
        [
            r["planner"],
            "yes" if r["success"] else f"no ({r['message'][:40]})",
            f"{r['planning_time']:.3f}",
            f"{r['round_trip']:.3f}",
            str(r["nodes"]),
            str(r["collision_checks"]),
            f"{r['path_length']:.2f}" if r["path_length"] is not None else "-",
        ]
        for r in rows
    ]
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(COLUMNS)]
    line = "| " + " | ".join(h.ljust(w) for h, w in zip(COLUMNS, widths)) + " |"
    sep = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    return [line, sep] + ["| " + " | ".join(c.ljust(w) for c, w in zip(row, widths)) + " |" for row in cells]


def trajectory_as_result(response) -> SimpleNamespace:
    """The parts of a MotionResult that ``plot_plan`` draws, read from a PlanMotion response."""
    traj = response.trajectory
    positions = np.array([p.positions for p in traj.points], dtype=float)
    times = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in traj.points]
    return SimpleNamespace(
        joint_names=list(traj.joint_names),
        path=positions,
        trajectory=SimpleNamespace(positions=positions, duration=times[-1] if times else 0.0),
        stats=SimpleNamespace(path_length=response.stats.path_length, solve_time=response.stats.solve_time),
    )


def draw_plan(rows, client, out_dir: Path) -> Path | None:
    solved = [r for r in rows if r["success"]]
    if not solved:
        return None
    best = next((r for r in solved if r["planner"] == PlannerConfig.default_planner), solved[0])
    scene = Scene.from_yaml(client.get_scene().scene_yaml)
    return plot_plan(
        RobotModel.maru1(),
        scene,
        trajectory_as_result(best["response"]),
        out_dir / "plan_13dof.png",
        title=f"Maru-1 13-DOF, {best['planner']} via plan_motion",
    )


def write_results(rows, out_dir: Path, table: list[str]) -> None:
    plain = [{k: v for k, v in r.items() if k != "response"} for r in rows]
    (out_dir / "demo.json").write_text(json.dumps(plain, indent=2))
    (out_dir / "demo.md").write_text("# Maru-1 13-DOF problem through plan_motion\n\n" + "\n".join(table) + "\n")


def main(argv=None) -> int:
    args = parse_args(argv)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    configure_loopback_dds(args.domain_id, random_domain=True)
    print(f"[demo] DDS on loopback only, ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']}", flush=True)

    # lazy: rclpy and its client load only once configure_loopback_dds has set the DDS environment
    import rclpy

    from maru_planner.ros.lifecycle import shut_down_context
    from maru_planner.ros.planning_client import PlanningClient

    problem = PROBLEMS["maru13"]
    joint_names = RobotModel.maru1().groups[problem.group]
    node, log_path = start_node(out_dir)
    print(f"[demo] started planning_node (pid {node.pid}, log {log_path})", flush=True)
    rclpy.init()
    client = None
    try:
        client = PlanningClient(node_name="maru_demo_client")
        try:
            client.wait_until_ready(timeout=90.0)
        except TimeoutError:
            print(f"[demo] planning_node did not answer; its log:\n{log_path.read_text()}", file=sys.stderr)
            return 1
        rows = run_planners(client, problem, joint_names, args.planners, args.time, args.seed)
        table = format_table(rows)
        print("\n" + "\n".join(table) + "\n")
        write_results(rows, out_dir, table)
        picture = draw_plan(rows, client, out_dir)
        print(f"[demo] wrote {out_dir / 'demo.json'}, {out_dir / 'demo.md'}" + (f", {picture}" if picture else ""))
        return 0 if any(r["success"] for r in rows) else 1
    finally:
        if client is not None:
            client.close()
        shut_down_context()
        node.terminate()
        try:
            node.wait(timeout=10)
        except subprocess.TimeoutExpired:
            node.kill()


if __name__ == "__main__":
    sys.exit(main())
