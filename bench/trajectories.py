"""Trajectory benchmark (issue 17): trapezoid vs toppra vs ruckig on planned paths.

    .venv/bin/python bench/trajectories.py [--quick] [--seeds 30] [--mbm 100]

Paths: the paper's 13-DOF and 6-DOF Maru-1 problems (``--seeds`` seeds each) and ``--mbm``
MotionBenchMaker Panda problems (spread over the sets), planned by ``MotionPlanner`` (RRTConnect,
sphere checker, verified on the exact model, shortcut). Every path is then time-parameterised by
each method of :mod:`maru_planner.trajectory` with the same limits, blend deviation and
blend certification as the planner uses (``PathCertifier`` through ``trajectory.certified_curve``: continuous,
the safety margin, toppra's blends as the parabolas they are, Ruckig's curves as chords ``resolution``
apart plus their error).

Reported per family and method: trajectory duration, its ratio to the trapezoids and to the
cruise-only lower bound (every segment at its fastest synchronised speed, no acceleration),
the largest velocity / acceleration / jerk over its limit (from a fine sampling: the reported
values and finite differences, jerk from differences of accelerations; ruckig only, the others
jump in acceleration), the largest distance from the planned path, the time spent parameterising
(without the certification of blends, reported apart) and collisions when the finely sampled
trajectory (joint step ≤ 0.005 rad) is re-checked on the exact model.

Writes bench/results/trajectories.{json,md} and trajectories_13dof.png (one 13-DOF trajectory,
trapezoids vs toppra vs ruckig).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from maru_planner.collision import CollisionChecker  # noqa: E402
from maru_planner.collision.certify import PathCertifier  # noqa: E402
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN, mbm_panda  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402
from maru_planner.scene.motion_bench_maker import iter_mbm_problems  # noqa: E402
from maru_planner.trajectory import (  # noqa: E402
    CERTIFY_STEP,
    METHODS,
    CertifiedCurve,
    Limits,
    certified_curve,
    deviation_from_path,
    parameterize,
)

RESULTS = ROOT / "bench" / "results"
from _common import data_dir, require_data, results_dir  # noqa: E402

TARBALL = data_dir("motionbenchmaker", "vamp_panda_problems.tar.bz2")
PANDA_ARM = [f"panda_joint{i}" for i in range(1, 8)]
TARGETS = {"maru13_toppra_over_trapezoid": 0.8, "parameterize_median_s": 0.005, "cruise_ratio_goal": 1.2}


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


@dataclass
class Case:
    """One planned path (rows: group configurations) and what checks it.

    Blends are certified as ``MotionPlanner`` does (``trajectory.certified_curve`` on ``PathCertifier``, the
    planner's safety margin); the finished trajectory is re-checked on the exact checker alone, finely.
    """

    family: str
    name: str
    joint_names: list[str]
    path: np.ndarray
    limits: Limits
    exact_checker: CollisionChecker
    certifier: PathCertifier
    base: np.ndarray  # full configuration: joints outside the group
    indices: list[int]
    check_cpu: float = 0.0  # thread CPU seconds spent in curve_free

    def full(self, states: np.ndarray) -> np.ndarray:
        out = np.repeat(self.base[None], len(states), axis=0)
        out[:, self.indices] = states
        return out

    @property
    def curve_free(self) -> _TimedCheck:
        check = certified_curve(self.certifier, self.base, self.indices, None, self.certifier.safety_margin)
        return _TimedCheck(check, self)


@dataclass
class _TimedCheck:
    """The planner's blend check (one certification pass per call, bent blends), its CPU time added to the case's."""

    check: CertifiedCurve
    case: Case
    takes_bends = True

    def __call__(self, states: np.ndarray, chord_deviation: np.ndarray) -> bool:
        return self.many([(states, chord_deviation)])[0]

    def many(self, curves: list) -> list[bool]:
        t0 = time.thread_time()
        free = self.check.many(curves)
        self.case.check_cpu += time.thread_time() - t0
        return free


# Every method below re-times the planner's path, some through its corners: plan with the timing that stops at them,
# so the planner certifies all of the path (a toppra plan leaves out the corners its blends round).
WHOLE_PATH = "trapezoid"


def planned_case(
    planner: MotionPlanner, family: str, name: str, request: MotionRequest, certifier: PathCertifier
) -> Case | None:
    result = planner.plan(request)
    if not result.success:
        log(f"  {name}: {result.status.value} {result.message}")
        return None
    robot = planner.robot
    indices = [robot.joint_names.index(n) for n in result.joint_names]
    base = np.asarray(robot.neutral(), float).copy()
    base[robot.joint_indices(list(request.start))] = list(request.start.values())
    limits = Limits.scaled(robot.velocity_limits[indices], robot.acceleration_limits[indices])
    return Case(family, name, list(result.joint_names), np.asarray(result.path), limits, certifier.checker,
                certifier, base, indices)  # fmt: skip


def paper_cases(family: str, seeds: int) -> list[Case]:
    problem = PROBLEMS[family]
    robot = RobotModel.maru1()
    planner = MotionPlanner.from_scene(
        robot, Scene.from_yaml(problem.scene_path), PlannerConfig(collision_model="spheres")
    )
    certifier = PathCertifier(robot, planner.exact_checker, planner.config.safety_margin)
    names = robot.groups[problem.group]
    start = dict(robot.named_states.get("home", {})) | problem.start_dict(names)  # as bench/paper000.py
    cases = []
    for seed in range(1, seeds + 1):
        request = MotionRequest(problem.group, start=start, goal_joints=problem.goal_dict(names),
                                planner_id="RRTConnect", time_budget=30.0, seed=seed,
                                time_parameterization=WHOLE_PATH)  # fmt: skip
        case = planned_case(planner, family, f"{family}/seed{seed}", request, certifier)
        if case is not None:
            cases.append(case)
        log(f"  planned {family} seed {seed}: {'ok' if case else 'failed'}")
    return cases


def mbm_cases(count: int) -> list[Case]:
    robot = mbm_panda()
    planner = MotionPlanner.from_scene(robot, None, PlannerConfig(collision_model="spheres"))
    problems = list(iter_mbm_problems(TARBALL, fixed_joints=PANDA_FINGERS_OPEN))
    chosen = [problems[int(i)] for i in np.linspace(0, len(problems) - 1, min(count, len(problems)))]
    cases = []
    for k, problem in enumerate(chosen):
        planner.set_scene(problem.scene)
        goal = {j: v for j, v in problem.request.goal.items() if j in PANDA_ARM}
        request = MotionRequest("arm", start=problem.request.start, goal_joints=goal, planner_id="RRTConnect",
                                time_budget=10.0, seed=k, time_parameterization=WHOLE_PATH)  # fmt: skip
        # a certifier of its own: the planner's follows the planner's next scene
        certifier = PathCertifier(robot, CollisionChecker(robot, problem.scene), planner.config.safety_margin)
        case = planned_case(planner, "mbm_panda", f"mbm/{problem.name}", request, certifier)
        if case is not None:
            cases.append(case)
        if (k + 1) % 10 == 0 or k + 1 == len(chosen):
            log(f"  planned {k + 1}/{len(chosen)} MotionBenchMaker problems")
    return cases


# ---------------------------------------------------------------------------------------- metrics --
def cruise_bound(path: np.ndarray, limits: Limits) -> float:
    """Every segment at its fastest synchronised speed, no acceleration: a lower bound on any duration."""
    return float(sum(np.max(np.abs(d) / limits.velocity) for d in np.diff(path, axis=0)))


def limit_ratios(traj, limits: Limits) -> tuple[float, float, float]:
    """Largest |v|/v_max, |a|/a_max, |jerk|/j_max from the samples alone (values and finite differences)."""
    dt = np.diff(traj.times)[:, None]
    v = max(np.max(np.abs(traj.velocities) / limits.velocity),
            np.max(np.abs(np.diff(traj.positions, axis=0)) / dt / limits.velocity))  # fmt: skip
    a = max(np.max(np.abs(traj.accelerations) / limits.acceleration),
            np.max(np.abs(np.diff(traj.velocities, axis=0)) / dt / limits.acceleration))  # fmt: skip
    j = np.max(np.abs(np.diff(traj.accelerations, axis=0)) / dt / limits.jerk)
    return float(v), float(a), float(j)


def measure(case: Case, method: str, config: PlannerConfig) -> tuple[dict, object]:
    t0, cpu0, check0 = time.perf_counter(), time.thread_time(), case.check_cpu
    traj, report = parameterize(case.path, case.joint_names, case.limits, method, curve_free=case.curve_free,
                                       max_deviation=config.blend_deviation, dt=config.trajectory_dt,
                                       max_points=config.max_trajectory_points,
                                       certify_step=config.resolution)  # fmt: skip
    elapsed = time.perf_counter() - t0
    cpu = time.thread_time() - cpu0 - (case.check_cpu - check0)
    fine_dt = CERTIFY_STEP / float(np.max(case.limits.velocity))
    fine, _ = parameterize(case.path, case.joint_names, case.limits, method, curve_free=case.curve_free,
                                  max_deviation=config.blend_deviation, dt=fine_dt, max_points=10**7,
                                  certify_step=config.resolution)  # fmt: skip
    v, a, j = limit_ratios(fine, case.limits)
    states = case.full(fine.positions)
    collisions = int(len(states) - np.count_nonzero(case.exact_checker.are_valid(states)))
    return {
        "case": case.name,
        "method": report.method,
        "duration": traj.duration,
        "cruise_bound": cruise_bound(case.path, case.limits),
        "points": len(traj.times),
        "parameterize_s": elapsed - report.certify_time,
        "parameterize_cpu_s": cpu,
        "certify_s": report.certify_time,
        "certify_checks": report.certify_checks,
        "velocity_ratio": v,
        "acceleration_ratio": a,
        "jerk_ratio": j if report.method == "ruckig" else None,  # the others jump in acceleration
        "max_deviation": float(deviation_from_path(fine.positions, case.path).max()),
        "blends": report.blends,
        "stops": report.stops,
        "fallbacks": len(report.fallbacks),
        "fine_samples": len(states),
        "collisions": collisions,
        "waypoints": len(case.path),
    }, fine


def summarize(rows: list[dict]) -> dict:
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"], {})[r["requested"]] = r
    out = {}
    for method in METHODS:
        mine = [r for r in rows if r["requested"] == method]
        if not mine:
            continue
        over_trap = [by_case[r["case"]][method]["duration"] / by_case[r["case"]]["trapezoid"]["duration"]
                     for r in mine if "trapezoid" in by_case[r["case"]]]  # fmt: skip
        jerks = [r["jerk_ratio"] for r in mine if r["jerk_ratio"] is not None]
        out[method] = {
            "cases": len(mine),
            "median_duration_s": float(np.median([r["duration"] for r in mine])),
            "median_over_trapezoid": float(np.median(over_trap)),
            "median_over_cruise_bound": float(np.median([r["duration"] / r["cruise_bound"] for r in mine])),
            "max_velocity_ratio": max(r["velocity_ratio"] for r in mine),
            "max_acceleration_ratio": max(r["acceleration_ratio"] for r in mine),
            "max_jerk_ratio": max(jerks) if jerks else None,
            "max_deviation_rad": max(r["max_deviation"] for r in mine),
            "median_parameterize_ms": 1e3 * float(np.median([r["parameterize_s"] for r in mine])),
            "p95_parameterize_ms": 1e3 * float(np.percentile([r["parameterize_s"] for r in mine], 95)),
            "median_parameterize_cpu_ms": 1e3 * float(np.median([r["parameterize_cpu_s"] for r in mine])),
            "median_certify_ms": 1e3 * float(np.median([r["certify_s"] for r in mine])),
            "collisions": sum(r["collisions"] for r in mine),
            "fine_samples": sum(r["fine_samples"] for r in mine),
            "fell_back_to_trapezoid": sum(r["method"] != method for r in mine),
            "corners_stopped": sum(r["stops"] for r in mine),
            "corners_blended": sum(r["blends"] for r in mine),
            "max_points": max(r["points"] for r in mine),
        }
    return out


# ---------------------------------------------------------------------------------------- outputs --
def plot(case: Case, fines: dict, path: Path) -> None:
    order = ("trapezoid", "toppra", "ruckig")
    fig, axes = plt.subplots(3, len(order), figsize=(5 * len(order), 9), sharex=True, sharey="row")
    for col, method in enumerate(order):
        traj = fines[method]
        for row, (values, label) in enumerate(((traj.positions, "position (rad)"),
                                               (traj.velocities, "velocity (rad/s)"),
                                               (traj.accelerations, "acceleration (rad/s²)"))):  # fmt: skip
            ax = axes[row, col]
            ax.plot(traj.times, values, lw=1)
            ax.grid(alpha=0.3)
            if col == 0:
                ax.set_ylabel(label)
        axes[0, col].set_title(f"{method}: {traj.duration:.2f} s" + (" (old)" if method == "trapezoid" else ""))
        axes[2, col].set_xlabel("time (s)")
    fig.suptitle(f"{case.name}: {len(case.path)} waypoints, 13 joints (limits: ±velocity, ±4 rad/s²)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(summary: dict, args, checks: dict) -> str:
    quick = " --quick" if args.quick else ""
    lines = [
        "# Trajectories: trapezoid vs toppra vs ruckig (issue 17)",
        "",
        f"Command: `.venv/bin/python bench/trajectories.py{quick} --seeds {args.seeds} --mbm {args.mbm}`. "
        f"Blend deviation {args.deviation} rad, sample period 0.05 s; limits re-checked on a sampling with joint "
        "steps ≤ 0.005 rad (values and finite differences); the same sampling re-checked for collision on the "
        "exact model. Blends certified as by MotionPlanner (PathCertifier, safety margin; toppra's as parabolas, "
        "Ruckig's as chords 0.02 rad apart). "
        "Parameterisation time excludes that certification of blends (listed apart); wall time "
        "depends on the machine's load, the 5 ms target is checked on CPU time.",
        "",
    ]
    head = (
        "| family | method | cases | median duration (s) | / trapezoid | / cruise bound | max v ratio | "
        "max a ratio | max j ratio | max deviation (rad) | param. wall median / p95, CPU median (ms) | "
        "re-check median (ms) | collisions | stops / blends | → trapezoid |"
    )
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    for family, per_method in summary.items():
        for method, s in per_method.items():
            j = "—" if s["max_jerk_ratio"] is None else f"{s['max_jerk_ratio']:.6f}"
            lines.append(
                f"| {family} | {method} | {s['cases']} | {s['median_duration_s']:.3f} | "
                f"{s['median_over_trapezoid']:.3f} | {s['median_over_cruise_bound']:.3f} | "
                f"{s['max_velocity_ratio']:.6f} | "
                f"{s['max_acceleration_ratio']:.6f} | {j} | {s['max_deviation_rad']:.3f} | "
                f"{s['median_parameterize_ms']:.2f} / {s['p95_parameterize_ms']:.2f}, "
                f"{s['median_parameterize_cpu_ms']:.2f} | {s['median_certify_ms']:.1f} | "
                f"{s['collisions']} / {s['fine_samples']} | {s['corners_stopped']} / {s['corners_blended']} | "
                f"{s['fell_back_to_trapezoid']} |"
            )
    lines += ["", "Targets:", ""] + [f"- {name}: {'met' if ok else 'NOT met'}" for name, ok in checks.items()]
    lines += ["", "![13-DOF trajectory](trajectories_13dof.png)", ""]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 seeds per paper problem, 5 MotionBenchMaker problems")
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--mbm", type=int, default=100, help="MotionBenchMaker Panda problems (spread over the sets)")
    ap.add_argument("--deviation", type=float, default=None, help="blend deviation (rad); default: PlannerConfig's")
    args = ap.parse_args()
    global RESULTS
    RESULTS = results_dir(args.quick)  # --quick: bench/results/quick/, never the committed results
    require_data(TARBALL)
    if args.quick:
        args.seeds, args.mbm = 3, 5
    config = PlannerConfig() if args.deviation is None else PlannerConfig(blend_deviation=args.deviation)
    args.deviation = config.blend_deviation
    t_start = time.monotonic()
    families = {}
    for family in ("maru13", "maru6"):
        log(f"planning {family}, {args.seeds} seeds")
        families[family] = paper_cases(family, args.seeds)
    log(f"planning {args.mbm} MotionBenchMaker Panda problems")
    families["mbm_panda"] = mbm_cases(args.mbm)

    rows, plotted = [], None
    total = sum(len(c) for c in families.values())
    done = 0
    for family, cases in families.items():
        for case in cases:
            fines = {}
            for method in METHODS:
                row, fines[method] = measure(case, method, config)
                row.update(family=family, requested=method)
                rows.append(row)
            done += 1
            log(
                f"[{done}/{total}] {case.name}: "
                + ", ".join(f"{r['requested']} {r['duration']:.2f} s" for r in rows[-3:])
                + f" ({time.monotonic() - t_start:.0f} s)"
            )
            if plotted is None and family == "maru13":
                plotted = (case, fines)

    summary = {family: summarize([r for r in rows if r["family"] == family]) for family in families}
    toppra13 = summary.get("maru13", {}).get("toppra", {})
    every = [s for per in summary.values() for s in per.values()]
    checks = {
        "13-DOF toppra median duration <= 0.8 x trapezoids": toppra13.get("median_over_trapezoid", 9) <= 0.8,
        "13-DOF toppra median <= 1.2 x cruise bound (goal)": toppra13.get("median_over_cruise_bound", 9) <= 1.2,
        "median parameterisation <= 5 ms CPU (toppra, every family)": all(
            per["toppra"]["median_parameterize_cpu_ms"] <= 5.0 for per in summary.values() if "toppra" in per),
        "every velocity / acceleration / jerk ratio <= 1 + 1e-6": all(
            s["max_velocity_ratio"] <= 1 + 1e-6 and s["max_acceleration_ratio"] <= 1 + 1e-6
            and (s["max_jerk_ratio"] is None or s["max_jerk_ratio"] <= 1 + 1e-6) for s in every),
        "0 collisions on the finely re-checked trajectories": all(s["collisions"] == 0 for s in every),
    }  # fmt: skip
    RESULTS.mkdir(parents=True, exist_ok=True)
    out = {"args": vars(args), "summary": summary, "targets": checks, "rows": rows,
           "seconds": time.monotonic() - t_start}  # fmt: skip
    (RESULTS / "trajectories.json").write_text(json.dumps(out, indent=1))
    (RESULTS / "trajectories.md").write_text(markdown(summary, args, checks))
    if plotted is not None:
        plot(plotted[0], plotted[1], RESULTS / "trajectories_13dof.png")
    print(markdown(summary, args, checks))


if __name__ == "__main__":
    main()
