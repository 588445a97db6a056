"""Fixed costs of ``MotionPlanner.plan``, stage by stage (issue 16: "trim the fixed costs").

    .venv/bin/python bench/plan_overhead.py [--repeats 50] [--mbm-per-set 10] [--planners CompiledRRTConnect,RRTConnect]
        [--profile] [--quick]

Requests, on the Maru-1 sphere checker (``collision_model="spheres"``, resolution 0.05 rad, no simplification):
- trivial: the 13-DOF start, goal 0.01 rad away on every joint, empty scene (one straight edge);
- maru13: paper problem 13-DOF (desk and box), seed = repeat index;

and on the MotionBenchMaker Panda with ``bench/peers_arm.py``'s configuration of ours (0.05 rad, 0.01 m margin, no
simplification, seed 0, each problem in its own scene):
- mbm: the first ``--mbm-per-set`` problems of each of the 7 sets;
- mbm, trapezoid: the same with ``time_parameterization="trapezoid"`` (stops at every waypoint, no blends to prove):
  what a path without TOPP-RA's blended trajectory costs.

Per stage, the median over the repeats of the facade's own timers (``PlanStats``): validation (start/goal
collision checks), search (OMPL setup + the planner's solve), simplification, time parameterisation,
certification (or the exact re-check; with the blends' proof when the whole curve was proven in that one pass, which
runs inside time parameterisation), and "request + setup" = the rest of the call (request checks, group
space, conversions, statistics). ``--profile`` prints cProfile's top functions of the trivial request. The
table also gives the median number of states the search checked.

Outputs bench/results/plan_overhead.{json,md,png} (the picture: stacked stage medians); the table on stdout.
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import pstats
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _common import RESULTS, Progress, require_data, write_results  # noqa: E402
from peers_arm import TARBALL, Case, Ours, mbm_cases  # noqa: E402

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.robots.panda import mbm_panda  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402

STAGES = ("request + setup", "validation", "search", "simplification", "time parameterisation", "certification")
MBM_BUDGET = 1.0  # s, as bench/peers_arm.py gives ours
Job = tuple[Scene, MotionRequest]


def requests(robot: RobotModel, planner_id: str, repeats: int) -> dict[str, list[Job]]:
    """The Maru-1 requests: trivial (empty scene) and maru13 (its desk and box), one per seed."""
    problem = PROBLEMS["maru13"]
    names = robot.groups[problem.group]
    start, goal = problem.start_dict(names), problem.goal_dict(names)
    near = {name: value + 0.01 for name, value in start.items()}

    def batch(scene: Scene, goal_joints: dict) -> list[Job]:
        return [(scene, MotionRequest(problem.group, start=start, goal_joints=goal_joints, planner_id=planner_id,
                                      time_budget=1.0, seed=seed, simplify=False))
                for seed in range(repeats)]  # fmt: skip

    return {"trivial": batch(Scene([]), near), "maru13": batch(Scene.from_yaml(problem.scene_path), goal)}


def mbm_jobs(ours: Ours, cases: list[Case]) -> dict[str, list[Job]]:
    """The MotionBenchMaker requests as ``bench/peers_arm.py`` makes ours (seed 0), and the same with trapezoids."""
    jobs = [(case.scene, ours.request(case, MBM_BUDGET, 0)) for case in cases]
    return {"mbm": jobs, "mbm, trapezoid": [(scene, dataclasses.replace(request, time_parameterization="trapezoid"))
                                           for scene, request in jobs]}  # fmt: skip


def stage_times(result) -> dict[str, float]:
    stats = result.stats
    # a curve proven with its blends (MotionResult.curve_proof) was certified inside time parameterisation: counted here
    proof = result.curve_proof.certify_time if result.curve_certified else 0.0
    certification = stats.certify_time if stats.certified else proof + stats.verify_time  # certify_time holds proof
    measured = {
        "validation": stats.validation_time,
        "search": stats.solve_time,
        "simplification": stats.simplify_time,
        "time parameterisation": stats.parameterize_time - proof,
        "certification": certification,
    }
    return {"request + setup": stats.total_time - sum(measured.values()), **measured, "total": stats.total_time}


def measure(planner: MotionPlanner, jobs: list[Job], progress: Progress, label: str) -> dict:
    """Plan every job (setting its scene when it changes; outside the timed call, as a user's scene update is)."""
    scene = jobs[0][0]
    planner.set_scene(scene)
    planner.plan(jobs[0][1])  # warm-up: numba loads its cached code, OMPL and toppra build their first objects
    rows, checked, solved = [], [], 0
    for job_scene, request in jobs:
        if job_scene is not scene:
            planner.set_scene(job_scene)
            scene = job_scene
        result = planner.plan(request)
        solved += result.success
        rows.append(stage_times(result))
        checked.append(result.stats.collision_checks)
        progress.step(label)
    return {"n": len(jobs), "solved": solved, "median_checked_states": float(np.median(checked)),
            "median_s": {k: float(np.median([r[k] for r in rows])) for k in (*STAGES, "total")}}  # fmt: skip


def profile(planner: MotionPlanner, request: MotionRequest, top: int = 30) -> None:
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(20):
        planner.plan(request)
    profiler.disable()
    pstats.Stats(profiler, stream=sys.stderr).sort_stats("cumulative").print_stats(top)


def markdown(results: dict) -> str:
    lines = ["# MotionPlanner.plan stage times (median ms per call)", "",
             "| request | planner | solved | " + " | ".join(STAGES) + " | total | states checked |",
             "|---|---|---|" + "---|" * (len(STAGES) + 2)]  # fmt: skip
    for key, row in results["runs"].items():
        name, planner_id = key.split("/")
        cells = " | ".join(f"{1e3 * row['median_s'][s]:.2f}" for s in (*STAGES, "total"))
        lines.append(f"| {name} | {planner_id} | {row['solved']}/{row['n']} | {cells} | "
                     f"{row['median_checked_states']:.0f} |")  # fmt: skip
    lines += ["", "Each stage's median is taken on its own, so the stages need not add up to the total's median."]
    return "\n".join(lines) + "\n"


def plot(results: dict, path: Path) -> None:
    """Stacked horizontal bars: each request's stage medians (ms), and issue 16's targets (Maru-1 1 ms, MBM 2 ms)."""
    runs = results["runs"]
    fig, ax = plt.subplots(figsize=(10, 0.45 * len(runs) + 2.4))
    left = np.zeros(len(runs))
    for stage in STAGES:
        width = np.array([1e3 * row["median_s"][stage] for row in runs.values()])
        ax.barh(list(runs), width, left=left, label=stage)
        left += width
    for target, label in ((1.0, "target: Maru-1 1 ms"), (2.0, "target: MotionBenchMaker 2 ms")):
        ax.axvline(target, color="gray", ls="--" if target < 2 else ":", lw=1, label=label)
    ax.invert_yaxis()
    ax.set_xlabel("median ms per MotionPlanner.plan call (stage medians, stacked)")
    ax.legend(fontsize=8, ncol=3, loc="lower center", bbox_to_anchor=(0.5, 1.0), frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50, help="requests per Maru-1 problem and planner")
    ap.add_argument("--mbm-per-set", type=int, default=10, help="MotionBenchMaker problems per set (0: none)")
    ap.add_argument("--planners", type=lambda text: text.split(","), default=["CompiledRRTConnect", "RRTConnect"])
    ap.add_argument("--profile", action="store_true", help="cProfile the trivial request (stderr)")
    ap.add_argument("--quick", action="store_true", help="5 repeats, 1 MotionBenchMaker problem per set")
    ap.add_argument("--out", type=Path, default=RESULTS / "plan_overhead")
    args = ap.parse_args(argv)
    if args.quick:
        args.repeats, args.mbm_per_set = 5, min(args.mbm_per_set, 1)
    if args.repeats < 1 or args.mbm_per_set < 0:
        ap.error("--repeats must be >= 1 and --mbm-per-set >= 0")
    if args.mbm_per_set > 0:
        require_data(TARBALL)  # or --mbm-per-set 0: the Maru-1 rows only
    robot = RobotModel.maru1()
    planner = MotionPlanner.from_scene(robot, None, PlannerConfig(collision_model="spheres", resolution=0.05))
    panda = mbm_panda() if args.mbm_per_set > 0 else None
    cases = mbm_cases(panda, args.mbm_per_set) if panda is not None else []
    results: dict = {"config": {"repeats": args.repeats, "mbm_per_set": args.mbm_per_set, "planners": args.planners},
                     "runs": {}}  # fmt: skip
    progress = Progress(len(args.planners) * 2 * (args.repeats + len(cases)))
    for planner_id in args.planners:
        for name, jobs in requests(robot, planner_id, args.repeats).items():
            results["runs"][f"{name}/{planner_id}"] = measure(planner, jobs, progress, f"{name}/{planner_id}")
        if cases:
            ours = Ours(panda, 0.05, 0.01, planner_id)
            for name, jobs in mbm_jobs(ours, cases).items():
                results["runs"][f"{name}/{planner_id}"] = measure(ours.planner, jobs, progress, f"{name}/{planner_id}")
    if args.profile:
        planner.set_scene(Scene([]))
        profile(planner, requests(robot, args.planners[0], 1)["trivial"][0][1])
    write_results(args.out, results, markdown(results), lambda path: plot(results, path), quick=args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
