"""Fixed costs of ``MotionPlanner.plan``, stage by stage (issue 16: "trim the fixed costs").

    .venv/bin/python bench/plan_overhead.py [--repeats 50] [--planners CompiledRRTConnect,RRTConnect] [--profile]

Requests, on the Maru-1 sphere checker (``collision_model="spheres"``, resolution 0.05 rad, no simplification):
- trivial: the 13-DOF start, goal 0.01 rad away on every joint, empty scene (one straight edge);
- maru13: paper problem 13-DOF (desk and box), seed = repeat index.

Per stage, the median over the repeats of the facade's own timers (``PlanStats``): validation (start/goal
collision checks), search (OMPL setup + the planner's solve), simplification, time parameterisation,
certification (or the exact re-check; with the blends' proof when the whole curve was proven in that one pass, which
runs inside time parameterisation), and "request + setup" = the rest of the call (request checks, group
space, conversions, statistics). ``--profile`` prints cProfile's top functions of the trivial request.

Outputs bench/results/plan_overhead.{json,md}; the table on stdout.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import sys
import time
from pathlib import Path

import numpy as np

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig
from maru_planner.planning.problems import PROBLEMS
from maru_planner.robot import RobotModel
from maru_planner.scene import Scene

RESULTS = Path(__file__).resolve().parent / "results"
STAGES = ("request + setup", "validation", "search", "simplification", "time parameterisation", "certification")


def requests(robot: RobotModel, planner_id: str, repeats: int) -> dict[str, tuple[Scene, list[MotionRequest]]]:
    problem = PROBLEMS["maru13"]
    names = robot.groups[problem.group]
    start, goal = problem.start_dict(names), problem.goal_dict(names)
    near = {name: value + 0.01 for name, value in start.items()}

    def batch(goal_joints: dict) -> list[MotionRequest]:
        return [MotionRequest(problem.group, start=start, goal_joints=goal_joints, planner_id=planner_id,
                              time_budget=1.0, seed=seed, simplify=False) for seed in range(repeats)]  # fmt: skip

    return {"trivial": (Scene([]), batch(near)), "maru13": (Scene.from_yaml(problem.scene_path), batch(goal))}


def stage_times(result) -> dict[str, float]:
    stats = result.stats
    # a curve proven with its blends (MotionResult.curve_proof) was certified inside time parameterisation: counted here
    proof = result.curve_proof.certify_time if result.curve_certified else 0.0
    certification = proof + (stats.certify_time if stats.certified else stats.verify_time)
    measured = {
        "validation": stats.validation_time,
        "search": stats.solve_time,
        "simplification": stats.simplify_time,
        "time parameterisation": stats.parameterize_time - proof,
        "certification": certification,
    }
    return {"request + setup": stats.total_time - sum(measured.values()), **measured, "total": stats.total_time}


def measure(planner: MotionPlanner, batch: list[MotionRequest]) -> dict:
    planner.plan(batch[0])  # warm-up: numba loads its cached code, OMPL and toppra build their first objects
    rows, solved = [], 0
    for request in batch:
        result = planner.plan(request)
        solved += result.success
        rows.append(stage_times(result))
    return {"n": len(batch), "solved": solved,
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
             "| request | planner | solved | " + " | ".join(STAGES) + " | total |",
             "|---|---|---|" + "---|" * (len(STAGES) + 1)]  # fmt: skip
    for key, row in results["runs"].items():
        name, planner_id = key.split("/")
        cells = " | ".join(f"{1e3 * row['median_s'][s]:.2f}" for s in (*STAGES, "total"))
        lines.append(f"| {name} | {planner_id} | {row['solved']}/{row['n']} | {cells} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50, help="requests per problem and planner")
    ap.add_argument("--planners", type=lambda text: text.split(","), default=["CompiledRRTConnect", "RRTConnect"])
    ap.add_argument("--profile", action="store_true", help="cProfile the trivial request (stderr)")
    ap.add_argument("--out", type=Path, default=RESULTS / "plan_overhead")
    args = ap.parse_args(argv)
    robot = RobotModel.maru1()
    planner = MotionPlanner.from_scene(robot, None, PlannerConfig(collision_model="spheres", resolution=0.05))
    results: dict = {"config": {"repeats": args.repeats, "planners": args.planners}, "runs": {}}
    for planner_id in args.planners:
        for name, (scene, batch) in requests(robot, planner_id, args.repeats).items():
            planner.set_scene(scene)
            t0 = time.monotonic()
            results["runs"][f"{name}/{planner_id}"] = measure(planner, batch)
            print(f"{name}/{planner_id}: {time.monotonic() - t0:.1f} s", file=sys.stderr)
    if args.profile:
        planner.set_scene(Scene([]))
        profile(planner, requests(robot, args.planners[0], 1)["trivial"][1][0])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".json").write_text(json.dumps(results, indent=1))
    table = markdown(results)
    args.out.with_suffix(".md").write_text(table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
