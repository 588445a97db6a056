"""Manipulation features (issue 15): Cartesian paths, constrained planning, dual-arm coordination.

    .venv/bin/python bench/manipulation.py [--quick] [--lines 50] [--constrained 20] [--dual-seeds 10]

Suites (all generated from fixed seeds, so a run is repeatable):

- ``cartesian``: per robot (Maru-1's right arm in the desk-and-box scene, Panda's arm in an empty scene),
  ``--lines`` straight line tasks: a random collision-free start with a well-conditioned hand (smallest
  singular value of the hand Jacobian >= 0.05), a random direction and length 0.05-0.30 m, orientation
  kept; ``MotionPlanner.cartesian_path`` (max step 1 cm, jump threshold 5). Reported: fraction achieved
  (mean, share of full lines), why lines stop, certified share, time (median, p95).
- ``constrained``: Panda, ``--constrained`` tasks: the hand kept upright within 0.1 rad about x and y
  (free about z) from a random start to a goal on the constraint (a random move projected onto it).
  Planned by CBiRRT with the constraint and by RRTConnect without; success, time, and the constraint
  violation along the sampled trajectory measured independently (scipy rotation vectors of the hand's
  rotation from the start's, not the planner's code).
- ``dual_arm``: ``maru13_dual_carry`` (planning/dual_arm.py) over ``--dual-seeds`` seeds: success, time,
  the hands' relative-pose error along the trajectory (translation mm, rotation rad, measured directly).

Writes bench/results/manipulation.{json,md,png}; progress on stderr.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import RESULTS, Progress, log, write_results  # noqa: E402

from maru_planner.collision import CollisionChecker  # noqa: E402
from maru_planner.paths import config_path  # noqa: E402
from maru_planner.planning import MotionPlanner, MotionRequest  # noqa: E402
from maru_planner.planning.cartesian import CartesianRequest  # noqa: E402
from maru_planner.planning.constraints import OrientationConstraint, PathConstraints  # noqa: E402
from maru_planner.planning.dual_arm import DUAL_CARRY, relative_pose_error  # noqa: E402
from maru_planner.planning.types import MotionResult, PlanStats, PlanStatus  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402
from maru_planner.trajectory import path_length  # noqa: E402

TOLERANCE = 0.1  # rad: the constrained suite's orientation tolerance about x and y
MIN_SINGULAR_VALUE = 0.05


# ------------------------------------------------------------------------------- cartesian --
ARMS = {  # robot -> (group, link, scene)
    "maru1": ("right_arm", "r_hand", "maru13_desk_box.yaml"),
    "panda": ("arm", "panda_hand_tcp", None),
}


def well_conditioned_start(robot, group: str, link: str, checker, rng) -> np.ndarray:
    """A collision-free configuration whose hand Jacobian (group joints) is far from singular."""
    indices = robot.group_joint_indices(group)
    base = robot.named_state("home") if "home" in robot.named_states else robot.named_state("default")
    while True:
        q = base.copy()
        q[indices] = rng.uniform(robot.lower_limits[indices], robot.upper_limits[indices])
        jacobian = robot.frame_jacobian(q, link)[:, indices]
        if np.linalg.svd(jacobian, compute_uv=False).min() >= MIN_SINGULAR_VALUE and checker.is_valid(q):
            return q


def cartesian_suite(robot_name: str, count: int, progress: Progress) -> list[dict]:
    group, link, scene_file = ARMS[robot_name]
    robot = RobotModel.from_profile(robot_name)
    scene = Scene.from_yaml(config_path("scenes", scene_file)) if scene_file else Scene()
    planner = MotionPlanner.from_scene(robot, scene)
    checker = CollisionChecker(robot, scene)
    rng = np.random.default_rng(15)
    runs = []
    for k in range(count):
        q = well_conditioned_start(robot, group, link, checker, rng)
        direction = rng.normal(size=3)
        offset = direction / np.linalg.norm(direction) * rng.uniform(0.05, 0.30)
        goal = robot.frame_pose(q, link).copy()
        goal[:3, 3] += offset
        request = CartesianRequest(group, dict(zip(robot.joint_names, q.tolist(), strict=True)), [goal], link=link,
                                   max_step=0.01, jump_threshold=5.0)  # fmt: skip
        t0 = time.monotonic()
        result = planner.cartesian_path(request)
        seconds = time.monotonic() - t0
        runs.append({"task": k, "length": float(np.linalg.norm(offset)), "status": result.status.value,
                     "fraction": result.fraction, "stop": _stop_kind(result.stop_reason, result.success),
                     "certified": result.certified, "seconds": seconds})  # fmt: skip
        progress.step(f"cartesian {robot_name} {k}: {result.fraction:.2f} ({runs[-1]['stop']}) {seconds:.3f} s")
    return runs


def _stop_kind(reason: str, success: bool) -> str:
    if success and not reason:
        return "complete"
    for key, kind in (("no IK", "unreachable"), ("jump", "jump"), ("collision", "collision"),
                      ("certified", "not certified"), ("time", "time")):  # fmt: skip
        if key in reason:
            return kind
    return "failed"


# ----------------------------------------------------------------------------- constrained --
def constrained_suite(count: int, budget: float, progress: Progress) -> list[dict]:
    robot = RobotModel.from_profile("panda")
    link, indices = "panda_hand_tcp", robot.group_joint_indices("arm")
    planner = MotionPlanner.from_scene(robot, Scene())
    checker = CollisionChecker(robot, Scene())
    rng = np.random.default_rng(150)
    runs: list[dict] = []
    while len(runs) < count:
        request, start, upright = constrained_suite_task(robot, checker, rng, seed=len(runs), budget=budget)
        run: dict = {"task": len(runs)}
        for mode in ("constrained", "unconstrained"):
            if mode == "unconstrained":
                request = dataclasses.replace(request, path_constraints=None, planner_id="RRTConnect")
            result = planner.plan(request)
            run[mode] = {"success": result.success, "status": result.status.value,
                         "seconds": result.stats.total_time,
                         "violation": tilt_violation(robot, start, indices, link, upright, result)}  # fmt: skip
        runs.append(run)
        progress.step(f"constrained {run['task']}: CBiRRT {run['constrained']['status']} "
                      f"{run['constrained']['seconds']:.2f} s, violation {run['constrained']['violation']}; "
                      f"RRTConnect violation {run['unconstrained']['violation']}")  # fmt: skip
    return runs


def constrained_suite_task(robot, checker, rng, seed: int = 0, budget: float = 10.0):
    """(request keeping the hand upright from a random start to a goal on the constraint, start, upright)."""
    link, indices = "panda_hand_tcp", robot.group_joint_indices("arm")
    while True:
        start = well_conditioned_start(robot, "arm", link, checker, rng)
        upright = robot.frame_pose(start, link)[:3, :3].copy()
        constraints = PathConstraints(OrientationConstraint(link, upright, np.array([TOLERANCE, TOLERANCE, math.pi])))
        moved = start.copy()
        moved[indices] += rng.uniform(-1.2, 1.2, len(indices))
        goal = constraints.project(robot, np.clip(moved, robot.lower_limits, robot.upper_limits), indices)
        if goal is not None and checker.is_valid(goal):
            request = MotionRequest(
                "arm", start=dict(zip(robot.joint_names, start.tolist(), strict=True)),
                goal_joints={robot.joint_names[i]: float(goal[i]) for i in indices}, seed=seed, time_budget=budget,
                path_constraints=constraints,
            )  # fmt: skip
            return request, start, upright


def tilt_violation(robot, start, indices, link, upright, result) -> float | None:
    """Largest excess over TOLERANCE of the x/y rotation-vector components along the sampled trajectory."""
    if not result.success:
        return None
    q, worst = start.copy(), 0.0
    for row in result.trajectory.positions:
        q[indices] = row
        rotvec = Rotation.from_matrix(upright.T @ robot.frame_pose(q, link)[:3, :3]).as_rotvec()
        worst = max(worst, float(np.abs(rotvec[:2]).max()) - TOLERANCE)
    return max(worst, 0.0)


# ------------------------------------------------------------------------------------ dual --
def dual_suite(seeds: int, budget: float, progress: Progress) -> list[dict]:
    robot = RobotModel.maru1()
    planner = MotionPlanner.from_scene(robot, DUAL_CARRY.scene())
    runs = []
    for seed in range(seeds):
        result = planner.plan(DUAL_CARRY.request(robot, seed=seed, time_budget=budget))
        run = {"seed": seed, "success": result.success, "status": result.status.value,
               "seconds": result.stats.total_time}  # fmt: skip
        if result.success:
            translation, rotation = relative_pose_error(robot, DUAL_CARRY, result.trajectory.positions)
            run.update(max_translation_mm=float(translation.max() * 1e3), max_rotation_rad=float(rotation.max()),
                       duration=result.trajectory.duration)  # fmt: skip
        runs.append(run)
        progress.step(f"dual-arm seed {seed}: {result.status.value} {run['seconds']:.2f} s "
                      f"{run.get('max_translation_mm', float('nan')):.2f} mm")  # fmt: skip
    return runs


# --------------------------------------------------------------------------------- summary --
def _pct(values, q: float) -> float | None:
    return float(np.percentile(values, q)) if len(values) else None


def summarize(results: dict) -> dict:
    summary: dict = {"cartesian": {}, "constrained": {}, "dual_arm": {}}
    for robot_name, runs in results["cartesian"].items():
        fractions = np.array([r["fraction"] for r in runs])
        seconds = np.array([r["seconds"] for r in runs])
        stops: dict[str, int] = {}
        for r in runs:
            stops[r["stop"]] = stops.get(r["stop"], 0) + 1
        summary["cartesian"][robot_name] = {
            "tasks": len(runs), "mean_fraction": float(fractions.mean()), "full": float((fractions == 1.0).mean()),
            "certified": float(np.mean([r["certified"] for r in runs])), "median_s": _pct(seconds, 50),
            "p95_s": _pct(seconds, 95), "stops": stops,
        }  # fmt: skip
    for mode in ("constrained", "unconstrained"):
        runs = [r[mode] for r in results["constrained"]]
        done = [r for r in runs if r["success"]]
        violations = [r["violation"] for r in done]
        summary["constrained"][mode] = {
            "tasks": len(runs), "success": len(done) / len(runs) if runs else None,
            "median_s": _pct([r["seconds"] for r in done], 50), "p95_s": _pct([r["seconds"] for r in done], 95),
            "max_violation": max(violations, default=None),
            "violating": sum(v > 1e-6 for v in violations),
        }  # fmt: skip
    dual = results["dual_arm"]
    done = [r for r in dual if r["success"]]
    summary["dual_arm"] = {
        "seeds": len(dual), "success": len(done) / len(dual) if dual else None,
        "median_s": _pct([r["seconds"] for r in done], 50),
        "max_translation_mm": max((r["max_translation_mm"] for r in done), default=None),
        "max_rotation_rad": max((r["max_rotation_rad"] for r in done), default=None),
    }  # fmt: skip
    return summary


def _f(value, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def markdown(summary: dict, args) -> str:
    lines = ["# Manipulation benchmark (bench/manipulation.py)", "",
             f"Command: `.venv/bin/python bench/manipulation.py{' --quick' if args.quick else ''}`", "",
             "## Cartesian lines (max step 1 cm, jump threshold 5, certified)", "",
             "| robot | tasks | mean fraction | full lines | certified | median s | p95 s | stops |",
             "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for name, s in summary["cartesian"].items():
        stops = ", ".join(f"{k} {v}" for k, v in sorted(s["stops"].items()))
        lines.append(f"| {name} | {s['tasks']} | {_f(s['mean_fraction'])} | {_f(s['full'], 2)} | "
                     f"{_f(s['certified'], 2)} | {_f(s['median_s'])} | {_f(s['p95_s'])} | {stops} |")  # fmt: skip
    lines += ["", f"## Panda hand upright (tolerance {TOLERANCE} rad about x and y), violation measured along the "
              "sampled trajectory", "",
              "| planner | tasks | success | median s | p95 s | max violation (rad) | violating paths |",
              "|---|---|---|---|---|---|---|"]  # fmt: skip
    for mode, label in (("constrained", "CBiRRT + constraint"), ("unconstrained", "RRTConnect, no constraint")):
        s = summary["constrained"][mode]
        lines.append(f"| {label} | {s['tasks']} | {_f(s['success'], 2)} | {_f(s['median_s'])} | {_f(s['p95_s'])} | "
                     f"{_f(s['max_violation'], 4)} | {s['violating']} |")  # fmt: skip
    d = summary["dual_arm"]
    lines += ["", "## Dual-arm carry (maru13_dual_carry, tolerance 1 mm / 0.01 rad per component)", "",
              "| seeds | success | median s | max translation error (mm) | max rotation error (rad) |",
              "|---|---|---|---|---|",
              f"| {d['seeds']} | {_f(d['success'], 2)} | {_f(d['median_s'])} | {_f(d['max_translation_mm'])} | "
              f"{_f(d['max_rotation_rad'], 4)} |", ""]  # fmt: skip
    return "\n".join(lines)


def plot(results: dict, path: Path) -> None:
    import matplotlib  # noqa: PLC0415 - only for the picture

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for name, runs in results["cartesian"].items():
        axes[0].hist([r["fraction"] for r in runs], bins=np.linspace(0, 1, 11), alpha=0.6, label=name)
    axes[0].set(title="Cartesian lines: fraction achieved", xlabel="fraction", ylabel="tasks")
    axes[0].legend()
    for mode, color in (("constrained", "tab:green"), ("unconstrained", "tab:red")):
        values = [r[mode]["violation"] for r in results["constrained"] if r[mode]["violation"] is not None]
        axes[1].plot(sorted(values), "o-", color=color, label=mode)
    axes[1].set(title=f"hand tilt beyond {TOLERANCE} rad along the trajectory", xlabel="task (sorted)",
                ylabel="violation (rad)")  # fmt: skip
    axes[1].legend()
    done = [r for r in results["dual_arm"] if r["success"]]
    axes[2].bar([str(r["seed"]) for r in done], [r["max_translation_mm"] for r in done], color="tab:blue")
    axes[2].axhline(math.sqrt(3), color="gray", linestyle="--", label="bound sqrt(3) x 1 mm")
    axes[2].set(title="dual-arm carry: hands' relative translation error", xlabel="seed", ylabel="max error (mm)")
    axes[2].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# -------------------------------------------------------------------------------- pictures --
SQUARE_START = (-0.9, 0.25, 1.75, 1.66, 1.9, 0.0, -2.55, 0.15, 1.35, 0.83, 1.87, -3.17, -1.41)


def pictures(out: Path) -> list[Path]:
    """A vertical Cartesian square (8 cm) of Maru-1's right hand, and the Panda hand kept upright (CBiRRT)."""
    from maru_planner.viz.plans import plot_plan  # noqa: PLC0415 - lazy: matplotlib only for the pictures

    written = []
    robot = RobotModel.maru1()
    scene = Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml"))
    q = np.array(SQUARE_START)
    corner = robot.frame_pose(q, "r_hand")
    square = []
    for offset in ((0.08, 0, 0), (0.08, 0, 0.08), (0, 0, 0.08), (0, 0, 0)):
        pose = corner.copy()
        pose[:3, 3] += offset
        square.append(pose)
    start = dict(zip(robot.joint_names, q.tolist(), strict=True))
    line = MotionPlanner.from_scene(robot, scene).cartesian_path(CartesianRequest("right_arm", start, square))
    if line.success:
        shown = MotionResult(PlanStatus.SUCCESS, joint_names=line.joint_names, path=line.path,
                             trajectory=line.trajectory,
                             stats=PlanStats(solve_time=line.seconds, path_length=path_length(line.path)))  # fmt: skip
        path = out.with_name(out.name + "_cartesian.png")
        plot_plan(robot, scene, shown, path, title=f"Cartesian square, r_hand: fraction {line.fraction:.2f}",
                  base_q=q)  # fmt: skip
        written.append(path)
    panda = RobotModel.from_profile("panda")
    checker = CollisionChecker(panda, Scene())
    task = constrained_suite_task(panda, checker, np.random.default_rng(150))
    result = MotionPlanner.from_scene(panda, Scene()).plan(task[0])
    if result.success:
        tilt = tilt_violation(panda, task[1], panda.group_joint_indices("arm"), "panda_hand_tcp", task[2], result)
        path = out.with_name(out.name + "_constrained.png")
        plot_plan(panda, Scene(), result, path, title=f"Panda hand upright (0.1 rad): violation {tilt:.4f} rad",
                  base_q=task[1])  # fmt: skip
        written.append(path)
    return written


# ------------------------------------------------------------------------------------ main --
def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="5 lines per robot, 3 constrained tasks, 2 dual-arm seeds")
    ap.add_argument("--lines", type=int, default=50, help="Cartesian line tasks per robot")
    ap.add_argument("--constrained", type=int, default=20, help="constrained planning tasks")
    ap.add_argument("--dual-seeds", type=int, default=10, help="seeds of the dual-arm problem")
    ap.add_argument("--budget", type=float, default=10.0, help="time budget per planning request (s)")
    ap.add_argument("--out", type=Path, default=RESULTS / "manipulation")
    args = ap.parse_args(argv)
    lines, constrained, seeds = (5, 3, 2) if args.quick else (args.lines, args.constrained, args.dual_seeds)
    progress = Progress(2 * lines + constrained + seeds)
    results = {
        "config": {"quick": args.quick, "lines": lines, "constrained": constrained, "dual_seeds": seeds,
                   "budget": args.budget, "tolerance": TOLERANCE},
        "cartesian": {name: cartesian_suite(name, lines, progress) for name in ARMS},
        "constrained": constrained_suite(constrained, args.budget, progress),
        "dual_arm": dual_suite(seeds, args.budget, progress),
    }  # fmt: skip
    results["summary"] = summarize(results)
    written = write_results(args.out, results, markdown(results["summary"], args), lambda path: plot(results, path),
                            quick=args.quick)  # fmt: skip
    for picture in pictures(written):
        log(f"picture {picture}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
