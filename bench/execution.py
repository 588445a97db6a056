"""Execution benchmark (issue 39): planned, certified trajectories executed on MuJoCo arms.

    .venv/bin/python bench/execution.py [--quick] [--mbm 100] [--seeds 10]

Trajectories: ``--mbm`` MotionBenchMaker problems (Panda, spread over the sets) and the paper's 13-DOF Maru-1
task x ``--seeds`` seeds, each planned by ``MotionPlanner`` (RRTConnect, sphere checker, certified) once per
time parameterisation: toppra and ruckig against the trapezoid baseline, at full velocity scaling. Each is
executed from its start state by ``execution.executor.ArmController`` (joint_trajectory_controller's
interpolation and tolerances: path 0.05 rad, goal 0.01 rad / 0.01 rad/s, MoveIt's duration monitor) on
``physics.arm_model`` (1 kHz, effort limits from the URDFs, the scene's obstacles as geoms) twice: with the default
:class:`ServoGains` (position + velocity feedback and the acceleration feedforward ``M(q) a``) and, the peer, with
feedback only (no feedforward: what a bare position-controlled joint does).

Per trajectory: max and RMS tracking error per joint, robot-obstacle contacts (MuJoCo's, with penetration
depth), overrun of the planned duration (until the goal tolerances hold), torque saturation steps, the
result code, and how far the planned points leave the joint limits (the arm's stops are in the simulation).
Summary per robot and method (``summary[robot][method]``, default servo; ``summary[robot]["feedback_only"]`` the
peer). Writes bench/results/execution.{json,md,png} (the picture: planned and
executed joint curves of one 13-DOF task); ``--quick`` (3 problems, 2 seeds) writes under bench/results/quick/.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from _common import RESULTS, Progress, log, write_results  # noqa: E402

from maru_planner.execution.executor import ArmController, ExecutionResult  # noqa: E402
from maru_planner.execution.interpolation import checked_points  # noqa: E402
from maru_planner.execution.tolerances import ResultCode  # noqa: E402
from maru_planner.paths import benchmarks_dir  # noqa: E402
from maru_planner.physics.arm_model import ArmModel, ServoGains, build_arm_model  # noqa: E402
from maru_planner.physics.arm_sim import ArmSim  # noqa: E402
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN, mbm_panda  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402
from maru_planner.scene.motion_bench_maker import iter_mbm_problems  # noqa: E402

TARBALL = benchmarks_dir() / "motionbenchmaker" / "vamp_panda_problems.tar.bz2"
PANDA_ARM = [f"panda_joint{i}" for i in range(1, 8)]
METHODS = ("toppra", "ruckig", "trapezoid")  # trapezoid: the baseline
SERVOS = {"default": ServoGains(), "feedback_only": ServoGains(acceleration_feedforward=False)}
TARGETS = {"contacts": 0, "max_tracking_error_rad": 0.02, "max_overrun": 0.05, "goal_tolerance_violations": 0}


class Task:
    """One planning problem: the robot, its planner on the problem's scene, start (full state) and goal."""

    def __init__(self, robot_name: str, name: str, planner: MotionPlanner, scene: Scene, group: str, start, goal):
        self.robot_name, self.name, self.planner, self.scene = robot_name, name, planner, scene
        self.group, self.start, self.goal = group, dict(start), dict(goal)
        robot = planner.robot
        self.q0 = np.asarray(robot.neutral(), dtype=float).copy()
        self.q0[robot.joint_indices(list(self.start))] = list(self.start.values())


def maru13_tasks(seeds: int) -> list[tuple[Task, int]]:
    problem = PROBLEMS["maru13"]
    robot = RobotModel.maru1()
    scene = Scene.from_yaml(problem.scene_path)
    planner = MotionPlanner.from_scene(robot, scene, PlannerConfig(collision_model="spheres"))
    names = robot.groups[problem.group]
    start = dict(robot.named_states.get("home", {})) | problem.start_dict(names)  # as bench/paper000.py
    task = Task("maru1", "maru13", planner, scene, problem.group, start, problem.goal_dict(names))
    return [(task, seed) for seed in range(1, seeds + 1)]


def mbm_tasks(count: int) -> list[tuple[Task, int]]:
    robot = mbm_panda()
    planner = MotionPlanner.from_scene(robot, None, PlannerConfig(collision_model="spheres"))
    problems = list(iter_mbm_problems(TARBALL, fixed_joints=PANDA_FINGERS_OPEN))
    chosen = [problems[int(i)] for i in np.linspace(0, len(problems) - 1, min(count, len(problems)))]
    tasks = []
    for k, p in enumerate(chosen):
        goal = {j: v for j, v in p.request.goal.items() if j in PANDA_ARM}
        tasks.append((Task("panda", f"mbm/{p.name}", planner, p.scene, "arm", p.request.start, goal), k))
    return tasks


def limit_excess(task: Task, joint_names: list[str], positions: np.ndarray) -> float:
    """How far (rad) the planned points leave the joint limits (0 inside)."""
    robot = task.planner.robot
    index = robot.joint_indices(joint_names)
    below = robot.lower_limits[index] - positions
    above = positions - robot.upper_limits[index]
    return float(max(0.0, np.max(below), np.max(above)))


def run_task(task: Task, seed: int, arms: dict[str, ArmModel], keep: dict) -> list[dict]:
    rows = []
    task.planner.set_scene(task.scene)
    for method in METHODS:
        request = MotionRequest(task.group, start=task.start, goal_joints=task.goal, planner_id="RRTConnect",
                                time_budget=10.0, seed=seed, time_parameterization=method)  # fmt: skip
        plan = task.planner.plan(request)
        for servo, arm in arms.items():
            row: dict = {"robot": task.robot_name, "task": task.name, "seed": seed, "method": method, "servo": servo}
            if not plan.success or plan.trajectory is None:
                rows.append(row | {"planned": False, "status": plan.status.value})
                continue
            tr = plan.trajectory
            points = checked_points(tr.joint_names, tr.times, tr.positions, tr.velocities, tr.accelerations)
            sim = ArmSim(arm)
            sim.reset(task.q0)
            t0 = time.perf_counter()
            result = ArmController(sim).run(points)
            excess = limit_excess(task, tr.joint_names, tr.positions)
            rows.append(row | measured(result, time.perf_counter() - t0, excess))
            if task.robot_name == "maru1" and method == "toppra" and servo == "default" and "curve" not in keep:
                keep["curve"] = (task.name, seed, result)
    return rows


def measured(result: ExecutionResult, wall: float, excess: float) -> dict:
    return {
        "planned": True,
        "code": result.code.name,
        "message": result.message,
        "duration_s": result.duration,
        "max_error_rad": float(np.max(result.max_error)),
        "rms_error_rad": float(np.max(result.rms_error)),
        "max_error_per_joint": result.max_error.round(5).tolist(),
        "rms_error_per_joint": result.rms_error.round(5).tolist(),
        "overrun": result.overrun,
        "contacts": [(c.link, c.obstacle, round(c.depth, 5)) for c in result.contacts],
        "max_penetration_m": result.max_penetration,
        "saturated_steps": result.saturated_steps,
        "limit_excess_rad": excess,
        "wall_s": wall,
    }


def summarize(rows: list[dict]) -> dict:
    done = [r for r in rows if r.get("planned")]
    overruns = [r["overrun"] for r in done if r["overrun"] is not None]
    return {
        "trajectories": len(done),
        "plan_failures": len(rows) - len(done),
        "successful": sum(r["code"] == ResultCode.SUCCESSFUL.name for r in done),
        "contacts": sum(len(r["contacts"]) for r in done),
        "trajectories_with_contact": sum(bool(r["contacts"]) for r in done),
        "max_penetration_m": max((r["max_penetration_m"] for r in done), default=0.0),
        "max_tracking_error_rad": max((r["max_error_rad"] for r in done), default=0.0),
        "p95_tracking_error_rad": float(np.percentile([r["max_error_rad"] for r in done], 95)) if done else 0.0,
        "rms_tracking_error_rad": float(np.sqrt(np.mean([r["rms_error_rad"] ** 2 for r in done]))) if done else 0.0,
        "max_overrun": max(overruns, default=None),
        "median_overrun": float(np.median(overruns)) if overruns else None,
        "goal_tolerance_violations": sum(r["code"] == ResultCode.GOAL_TOLERANCE_VIOLATED.name for r in done),
        "path_tolerance_violations": sum(r["code"] == ResultCode.PATH_TOLERANCE_VIOLATED.name for r in done),
        "torque_saturation_steps": sum(r["saturated_steps"] for r in done),
        "trajectories_leaving_joint_limits": sum(r["limit_excess_rad"] > 1e-6 for r in done),
        "max_limit_excess_rad": max((r["limit_excess_rad"] for r in done), default=0.0),
    }


def _fmt(value) -> str:
    if value is None:
        return "-"
    return f"{value:.4f}" if isinstance(value, float) else str(value)


def _table(summary: dict, which: str) -> list[str]:
    lines = [
        "| robot | method | traj | ok | contacts | max err (rad) | p95 err | RMS err | max overrun | goal viol. "
        "| path viol. | sat. steps | beyond limits (max rad) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for robot, per_servo in summary.items():
        for method, s in (per_servo if which == "default" else per_servo[which]).items():
            if method in ("all", "feedback_only"):
                continue
            lines.append(
                f"| {robot} | {method} | {s['trajectories']} | {s['successful']} | {s['contacts']} "
                f"| {_fmt(s['max_tracking_error_rad'])} | {_fmt(s['p95_tracking_error_rad'])} "
                f"| {_fmt(s['rms_tracking_error_rad'])} | {_fmt(s['max_overrun'])} | {s['goal_tolerance_violations']} "
                f"| {s['path_tolerance_violations']} | {s['torque_saturation_steps']} "
                f"| {s['trajectories_leaving_joint_limits']} ({_fmt(s['max_limit_excess_rad'])}) |"
            )
    return lines


def markdown(summary: dict, gains: dict, args, checks: dict) -> str:
    quick = " --quick" if args.quick else ""
    lines = [
        "# Trajectory execution in MuJoCo (issue 39)",
        "",
        f"Command: `.venv/bin/python bench/execution.py{quick} --mbm {args.mbm} --seeds {args.seeds}`. Planned by "
        "MotionPlanner (RRTConnect, spheres, certified), full velocity scaling; executed with "
        "joint_trajectory_controller's interpolation and tolerances (path 0.05 rad, goal 0.01 rad and 0.01 rad/s, "
        "MoveIt's 1.2 x duration + 0.5 s monitor) at 1 kHz. Trapezoid is the baseline. Overrun: (time the goal "
        "tolerances first hold - planned duration) / planned duration.",
        "",
        "Default servo (position + velocity feedback, acceleration feedforward):",
        "",
        *_table(summary, "default"),
        "",
        "Peer: the same trajectories on the same arms with feedback only (no acceleration feedforward):",
        "",
        *_table(summary, "feedback_only"),
    ]
    lines += ["", "Servo (default `ServoGains`): " + "; ".join(f"{k}: {v}" for k, v in gains.items()), "",
              "Targets (all trajectories of a robot): " + ", ".join(f"{k} {'met' if v else 'NOT met'}"
                                                                   for k, v in checks.items())]  # fmt: skip
    return "\n".join(lines) + "\n"


def plot_curve(path: Path, keep: dict) -> None:
    if "curve" not in keep:
        plt.figure().savefig(path)
        return
    name, seed, result = keep["curve"]
    names = result.joint_names
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 1.2 * len(names)), sharex=True, squeeze=False)
    for j, (ax, err) in enumerate(axes):
        ax.plot(result.times, result.desired[:, j], "C0-", lw=1.5, label="planned (interpolated)")
        ax.plot(result.times, result.actual[:, j], "C3--", lw=1.0, label="executed")
        ax.set_ylabel(names[j], rotation=0, ha="right", fontsize=7)
        err.plot(result.times, 1e3 * result.error[:, j], "k-", lw=0.8)
        err.set_ylabel("mrad", fontsize=6)
        for a in (ax, err):
            a.tick_params(labelsize=6)
    axes[0, 0].legend(fontsize=7, loc="lower right")
    axes[0, 0].set_title("joint position (rad)", fontsize=8)
    axes[0, 1].set_title("tracking error planned - executed (mrad)", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    fig.suptitle(f"{name} seed {seed}, toppra: max tracking error {np.max(result.max_error):.4f} rad", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="3 MotionBenchMaker problems and 2 seeds")
    ap.add_argument("--mbm", type=int, default=100, help="MotionBenchMaker problems (Panda)")
    ap.add_argument("--seeds", type=int, default=10, help="seeds of the 13-DOF task")
    args = ap.parse_args(argv)
    if args.quick:
        args.mbm, args.seeds = min(args.mbm, 3), min(args.seeds, 2)
    log("planning and executing ...")
    tasks = maru13_tasks(args.seeds) + mbm_tasks(args.mbm)
    progress, rows = Progress(len(tasks)), []
    keep: dict[str, Any] = {}
    gains: dict[str, Any] = {}
    models: dict[str, dict[str, ArmModel]] = {}
    for task, seed in tasks:
        if task.name not in models:
            robot = task.planner.robot
            models = {task.name: {s: build_arm_model(robot, task.scene, g, q0=task.q0) for s, g in SERVOS.items()}}
        arms = models[task.name]
        arm = arms["default"]
        gains.setdefault(f"{task.robot_name} kp (N m/rad)", sorted(set(arm.kp.round(0).tolist())))
        gains.setdefault(f"{task.robot_name} kv at start (N m s/rad)", f"{arm.kv.min():.1f}..{arm.kv.max():.1f}")
        rows += run_task(task, seed, arms, keep)
        progress.step(f"{task.name} seed {seed}")
    summary: dict = {}
    for robot in dict.fromkeys(r["robot"] for r in rows):
        mine = [r for r in rows if r["robot"] == robot and r["servo"] == "default"]
        peer = [r for r in rows if r["robot"] == robot and r["servo"] == "feedback_only"]
        summary[robot] = {m: summarize([r for r in mine if r["method"] == m]) for m in METHODS}
        summary[robot]["all"] = summarize(mine)
        summary[robot]["feedback_only"] = {m: summarize([r for r in peer if r["method"] == m]) for m in METHODS}
        summary[robot]["feedback_only"]["all"] = summarize(peer)
    checks = {
        f"{robot}_{name}": (s["all"][name] is not None and s["all"][name] <= limit)
        for robot, s in summary.items()
        for name, limit in TARGETS.items()
    }
    gains["saturation_error (kp = effort / it)"] = ServoGains().saturation_error
    gains["damping_ratio"] = ServoGains().damping_ratio
    gains["armature (kg m^2)"] = ServoGains().armature
    gains["gravity_compensation"] = ServoGains().gravity_compensation
    gains["acceleration_feedforward"] = ServoGains().acceleration_feedforward
    results = {"args": vars(args), "summary": summary, "targets": checks, "gains": gains, "rows": rows}
    write_results(RESULTS / "execution", results, markdown(summary, gains, args, checks),
                  lambda path: plot_curve(path, keep), quick=args.quick)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
