"""Certified arm paths (issue 13): does any returned path collide, and what does the proof cost?

    .venv/bin/python bench/certify.py [--quick] [--seeds 30] [--budget 1.0] [--models exact spheres]

Suites, each planned twice through ``MotionPlanner.plan`` -- certified (``PlannerConfig.certify``, the
default: every returned path proven collision-free on the exact model with ``--margin``, failing segments
repaired) and the uncertified baseline (today's discrete checks: the search's, plus the exact re-check of
a sphere plan at ``verify_step``):

- ``paper``: the 6-DOF and 13-DOF problems of paper 000 (``planning/problems.py``), every registered
  planner, ``--seeds`` seeds;
- ``mbm``: the 700 MotionBenchMaker Panda problems (the default planner, ``PlannerConfig().default_planner``:
  CompiledRRTConnect, OMPL's RRTConnect on the exact checker; seed 0).

Each collision model of ``--models`` plans every suite. Every returned motion (the trajectory's samples joined
by straight lines; the path for a plan without one) is re-checked independently on a fresh exact checker at
``--fine`` rad (default 0.001): a colliding path is one with a state in collision there. Reported: success
rate, colliding paths, median/p95 certification time and its share
of the median plan time (and what certification adds to the baseline's median), min clearance, repairs.

Writes bench/results/certify.{json,md,png}; progress on stderr.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from _common import RESULTS, Progress, log, require_data, write_results  # noqa: E402
from peers_arm import TARBALL, mbm_cases  # noqa: E402

from maru_planner.collision import CollisionChecker  # noqa: E402
from maru_planner.collision.spheres import densify  # noqa: E402
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.planners.registry import planner_ids  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.robots.panda import mbm_panda  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402

MODES = ("certified", "baseline")
SHARE_TARGET = 0.30  # issue 13: certification adds at most 30 % to the median plan time on MBM


class Case:
    """One problem: its scene and a request without planner id, budget and seed."""

    def __init__(self, name: str, suite: str, robot, scene: Scene, group: str, start: dict, goal: dict):
        self.name, self.suite, self.robot, self.scene = name, suite, robot, scene
        self.group, self.start, self.goal = group, start, goal

    def request(self, planner_id: str, budget: float, seed: int) -> MotionRequest:
        return MotionRequest(self.group, start=dict(self.start), goal_joints=dict(self.goal),
                             planner_id=planner_id, time_budget=budget, seed=seed)  # fmt: skip


def paper_cases(robot: RobotModel) -> list[Case]:
    """maru6 and maru13 with the rest of the robot at its "home" state (as bench/paper000.py)."""
    cases = []
    for name in ("maru6", "maru13"):
        prob = PROBLEMS[name]
        names = robot.groups[prob.group]
        start = dict(robot.named_states.get("home", {}))
        start.update(prob.start_dict(names))
        cases.append(Case(name, "paper", robot, Scene.from_yaml(prob.scene_path), prob.group, start,
                          prob.goal_dict(names)))  # fmt: skip
    return cases


def mbm(robot, per_set: int | None) -> list[Case]:
    return [Case(c.name, "mbm", robot, c.scene, c.group, c.start, c.goal) for c in mbm_cases(robot, per_set)]


# ------------------------------------------------------------------------------------------- running --
def fine_collides(robot, scene: Scene, request: MotionRequest, result, step: float) -> bool:
    """Whether the returned motion has a state in collision at ``step`` rad on a fresh exact checker: the
    trajectory's samples joined by straight lines (as a controller interpolates them; certification proves the
    trajectory's curve, which leaves the path at the corners its blends round)."""
    q = np.asarray(robot.neutral(), dtype=float).copy()
    q[robot.joint_indices(list(request.start))] = list(request.start.values())
    motion = result.trajectory.positions if result.trajectory is not None else result.path
    path = np.repeat(q[None], len(motion), axis=0)
    path[:, robot.joint_indices(list(result.joint_names))] = motion
    states, _ = densify(path, step)
    return CollisionChecker(robot, scene).first_invalid(states) >= 0


def run_one(planner: MotionPlanner, case: Case, planner_id: str, budget: float, seed: int, fine: float) -> dict:
    request = case.request(planner_id, budget, seed)
    result = planner.plan(request)
    stats = result.stats
    row = {
        "problem": case.name, "planner": planner_id, "seed": seed, "success": result.success,
        "status": result.status.value, "total_time": stats.total_time, "certified": stats.certified,
        "certify_time": stats.certify_time, "recheck_time": max(stats.certify_time, stats.verify_time),
        "repairs": stats.repairs,
        "min_clearance": stats.min_clearance if math.isfinite(stats.min_clearance) else None,
        "waypoints": stats.waypoints, "collides": None,
    }  # fmt: skip
    if result.success:
        row["collides"] = fine_collides(case.robot, case.scene, request, result, fine)
    return row


def planners_for(robot, model: str, args) -> dict[str, MotionPlanner]:
    """One planner per mode on ``model``; scenes are set per case."""
    base = dict(collision_model=model, resolution=args.resolution, safety_margin=args.margin)
    return {mode: MotionPlanner.from_scene(robot, None, PlannerConfig(certify=mode == "certified", **base))
            for mode in MODES}  # fmt: skip


def run_suite(cases: list[Case], jobs: list[tuple[str, int]], args, progress: Progress) -> dict:
    """{model: {mode: [row, ...]}} for every case x (planner id, seed) job."""
    out: dict = {}
    for model in args.models:
        planners = planners_for(cases[0].robot, model, args)
        out[model] = {mode: [] for mode in MODES}
        for case in cases:
            for planner in planners.values():
                planner.set_scene(case.scene)
            for planner_id, seed in jobs:
                for mode, planner in planners.items():
                    out[model][mode].append(run_one(planner, case, planner_id, args.budget, seed, args.fine))
                progress.step(f"{case.suite} {model} {case.name} {planner_id} {seed}")
    return out


def warm_up(robot, case: Case, args) -> None:
    """One untimed plan per model and mode: numba loads its cached code, OMPL and coal build first objects."""
    for model in args.models:
        for planner in planners_for(robot, model, args).values():
            planner.set_scene(case.scene)
            planner.plan(case.request("RRTConnect", args.budget, 0))


# ----------------------------------------------------------------------------------------- reporting --
def _median(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.median(values)) if values else None


def _p95(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.percentile(values, 95)) if values else None


def summarise(rows: list[dict], baseline: list[dict] | None = None) -> dict:
    ok = [r for r in rows if r["success"]]
    clearances = [r["min_clearance"] for r in ok if r["min_clearance"] is not None]
    out = {
        "runs": len(rows),
        "success": len(ok),
        "success_rate": len(ok) / len(rows) if rows else 0.0,
        "colliding_paths": sum(bool(r["collides"]) for r in ok),
        "median_total_s": _median([r["total_time"] for r in ok]),
        "median_certify_s": _median([r["recheck_time"] for r in ok]),
        "p95_certify_s": _p95([r["recheck_time"] for r in ok]),
        "min_clearance_m": min(clearances) if clearances else None,
        "median_min_clearance_m": _median(clearances),
        "repairs": sum(r["repairs"] for r in rows),
        "runs_repaired": sum(r["repairs"] > 0 for r in rows),
        "failures": sorted({f"{r['problem']} {r['planner']}: {r['status']}" for r in rows if not r["success"]})[:30],
    }
    if out["median_total_s"] and out["median_certify_s"] is not None:
        out["certify_share"] = out["median_certify_s"] / out["median_total_s"]
    if baseline:
        base = _median([r["total_time"] for r in baseline if r["success"]])
        if base and out["median_total_s"]:
            out["added_to_baseline"] = out["median_total_s"] / base - 1.0
    return out


def _select(rows: list[dict], key: tuple[str, str] | None) -> list[dict]:
    """The rows of one (problem, planner) pair; all rows for ``None``."""
    return rows if key is None else [r for r in rows if (r["problem"], r["planner"]) == key]


def build_summary(results: dict) -> dict:
    summary: dict = {}
    for suite, by_model in results["runs"].items():
        for model, by_mode in by_model.items():
            groups = {"all": None}
            if suite == "paper":
                groups.update({f"{r['problem']} {r['planner']}": (r["problem"], r["planner"])
                               for r in by_mode["certified"]})  # fmt: skip
            for label, key in groups.items():
                base = _select(by_mode["baseline"], key)
                summary[f"{suite} | {model} | {label}"] = {
                    "certified": summarise(_select(by_mode["certified"], key), base),
                    "baseline": summarise(base),
                }
    return summary


def _ms(x) -> str:
    return "—" if x is None else f"{1e3 * x:.1f}"


def _pct(x) -> str:
    return "—" if x is None else f"{100 * x:.0f} %"


def _mm(x) -> str:
    return "—" if x is None else f"{1e3 * x:.2f}"


def markdown(summary: dict, args) -> str:
    lines = [
        "# Certified arm paths (issue 13)",
        "",
        f"Budget {args.budget} s, resolution {args.resolution} rad, safety margin {args.margin} m, independent "
        f"re-check of every returned path at {args.fine} rad on a fresh exact checker. Certified: "
        "`PlannerConfig.certify` (proof on the exact model, local repair); baseline: discrete checks only. "
        "Times are medians over successful runs; the certify columns of a baseline are its exact re-check "
        "(spheres: discrete at `verify_step`; exact: none). Paper suite: every registered planner; MotionBenchMaker: "
        f"the default planner ({PlannerConfig().default_planner}; OMPL's RRTConnect on the exact checker).",
        "",
        "| suite | model | problems | mode | success | colliding paths | median plan ms | median certify ms "
        "| p95 certify ms | certify share | adds to baseline | min clearance mm | repairs (runs) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for key, modes in summary.items():
        suite, model, label = key.split(" | ")
        for mode, s in modes.items():
            lines.append(
                f"| {suite} | {model} | {label} | {mode} | {s['success']}/{s['runs']} | {s['colliding_paths']} | "
                f"{_ms(s['median_total_s'])} | {_ms(s['median_certify_s'])} | {_ms(s['p95_certify_s'])} | "
                f"{_pct(s.get('certify_share'))} | {_pct(s.get('added_to_baseline'))} | "
                f"{_mm(s['min_clearance_m'])} | {s['repairs']} ({s['runs_repaired']}) |"
            )
    lines += summary_table(summary, args)
    lines += ["", "## Targets", ""]
    for key, modes in summary.items():
        if not key.endswith("| all"):
            continue
        cert = modes["certified"]
        lines.append(f"- {'MET' if cert['colliding_paths'] == 0 else 'MISSED'}  {key}: "
                     f"0 colliding certified paths (found {cert['colliding_paths']}; baseline "
                     f"{modes['baseline']['colliding_paths']})")  # fmt: skip
        if key.startswith("mbm"):
            added = cert.get("added_to_baseline")
            met = added is not None and added <= SHARE_TARGET
            lines.append(
                f"- {'MET' if met else 'MISSED'}  {key}: certification adds <= 30 % to the median plan "
                f"time (adds {_pct(added)}; certification is {_pct(cert.get('certify_share'))} of it)"
            )
    return "\n".join(lines) + "\n"


def summary_table(summary: dict, args) -> list[str]:
    """Each suite and model over all its planners: the table the README quotes (same run, same numbers)."""
    suites = {"paper": f"paper 6- and 13-DOF, every planner × {args.seeds} seeds", "mbm": "MotionBenchMaker Panda"}
    lines = [
        "",
        "## Summary",
        "",
        "| problems | model | colliding paths: certified / baseline | success: certified / baseline "
        "| median certify ms | certify share of the plan | baseline's median re-check ms "
        "| certification adds to the median plan |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, modes in summary.items():
        suite, model, label = key.split(" | ")
        if label != "all":
            continue
        cert, base = modes["certified"], modes["baseline"]
        recheck = _ms(base["median_certify_s"]) if model == "spheres" else "none"  # exact: nothing to re-check
        lines.append(
            f"| {suites.get(suite, suite)} | {model} | **{cert['colliding_paths']}** / {base['colliding_paths']} | "
            f"{cert['success']} / {base['success']} of {cert['runs']} | {_ms(cert['median_certify_s'])} | "
            f"{_pct(cert.get('certify_share'))} | {recheck} | "
            f"{_pct(cert.get('added_to_baseline'))} |"
        )
    return lines


def plot(summary: dict, path: Path) -> None:
    import matplotlib  # lazy: only the report needs it

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = [k for k in summary if k.endswith("| all")]
    labels = [k.replace(" | all", "") for k in keys]
    x = np.arange(len(keys))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    for offset, mode in ((-0.2, "baseline"), (0.2, "certified")):
        ax1.bar(x + offset, [summary[k][mode]["colliding_paths"] for k in keys], 0.4, label=mode)
    ax1.set_title("returned paths colliding at the fine re-check")
    ax1.set_xticks(x, labels, rotation=20)
    ax1.legend()
    plan = [(summary[k]["certified"]["median_total_s"] or 0) * 1e3 for k in keys]
    cert = [(summary[k]["certified"]["median_certify_s"] or 0) * 1e3 for k in keys]
    base = [(summary[k]["baseline"]["median_total_s"] or 0) * 1e3 for k in keys]
    ax2.bar(x - 0.2, base, 0.4, label="baseline plan")
    ax2.bar(x + 0.2, plan, 0.4, label="certified plan")
    ax2.bar(x + 0.2, cert, 0.4, label="of which certification", hatch="//", fill=False)
    ax2.set_ylabel("median ms")
    ax2.set_title("plan time")
    ax2.set_xticks(x, labels, rotation=20)
    ax2.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# -------------------------------------------------------------------------------------------- main --
def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2 seeds on the paper problems, 1 MBM problem per set")
    ap.add_argument("--seeds", type=int, default=30, help="seeds per paper problem and planner")
    ap.add_argument("--per-set", type=int, default=None, help="MBM problems per set (default: all 100)")
    ap.add_argument("--budget", type=float, default=1.0, help="time budget per request (s)")
    ap.add_argument("--models", nargs="+", default=["exact", "spheres"], choices=["exact", "spheres"])
    ap.add_argument("--suites", nargs="+", default=["paper", "mbm"], choices=["paper", "mbm"])
    ap.add_argument("--resolution", type=float, default=PlannerConfig.resolution, help="search motion step (rad)")
    ap.add_argument("--margin", type=float, default=PlannerConfig.safety_margin, help="safety margin (m)")
    ap.add_argument("--fine", type=float, default=0.001, help="step of the independent re-check (rad)")
    ap.add_argument("--out", type=Path, default=RESULTS / "certify")
    args = ap.parse_args(argv)
    if "mbm" in args.suites:
        require_data(TARBALL)  # or --suites paper
    seeds = 2 if args.quick else args.seeds
    per_set = 1 if args.quick else args.per_set

    log("loading robots and problems ...")
    suites: dict[str, tuple[list[Case], list[tuple[str, int]]]] = {}
    if "paper" in args.suites:
        suites["paper"] = (paper_cases(RobotModel.maru1()), [(p, s) for p in planner_ids() for s in range(seeds)])
    if "mbm" in args.suites:
        suites["mbm"] = (mbm(mbm_panda(), per_set), [(PlannerConfig().default_planner, 0)])
    total = sum(len(cases) * len(jobs) for cases, jobs in suites.values()) * len(args.models)
    log(f"{total} problem x planner x seed x model runs, each planned certified and baseline")
    results: dict = {"config": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
                     "runs": {}}  # fmt: skip
    progress = Progress(total)
    for suite, (cases, jobs) in suites.items():
        warm_up(cases[0].robot, cases[-1], args)
        results["runs"][suite] = run_suite(cases, jobs, args, progress)
    summary = results["summary"] = build_summary(results)
    write_results(args.out, results, markdown(summary, args), lambda path: plot(summary, path), quick=args.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
