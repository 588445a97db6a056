"""RC-RRT's compiled search loop against its Python loop, on the paper's 6-DOF and 13-DOF problems (issue 16).

    .venv/bin/python bench/rcrrt_loop.py [--seeds 30] [--quick]

Every request goes through ``MotionPlanner.plan`` with ``PlannerConfig()`` (sphere checker, 0.02 rad, 1 cm margin,
certification, toppra) and planner "RCRRT", one seed per request, the same seeds for each loop:

- compiled: what a user gets (the loop in :mod:`maru_planner.planning.planners.kernels.rcrrt`);
- Python loop: the same planner with its compiled loop switched off (the baseline: the loop before issue 16);
- Python loop, exact checker: ``collision_model="exact"`` (what ``bench/paper000.py`` measures by default).

Reported per problem and loop: success, median and p95 search time and whole-request time, nodes, collision checks
(states, the exact model's confirmations included). Writes bench/results/rcrrt_loop.{json,md,png}.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from unittest import mock

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import RESULTS, Progress, log, write_results  # noqa: E402

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.planners.rc_rrt import RCRRT  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402

LOOPS = ("compiled", "Python loop", "Python loop, exact checker")
BUDGET = 10.0  # s per request (paper000's RC-RRT budget)


def requests(robot: RobotModel, name: str, seeds: int) -> list[MotionRequest]:
    """The problem's requests, one per seed; joints outside its group at the robot's "home" (as paper000's)."""
    problem = PROBLEMS[name]
    names = robot.groups[problem.group]
    start = {**robot.named_states.get("home", {}), **problem.start_dict(names)}
    return [MotionRequest(problem.group, start=start, goal_joints=problem.goal_dict(names), planner_id="RCRRT",
                          time_budget=BUDGET, seed=seed) for seed in range(seeds)]  # fmt: skip


def run_loop(robot: RobotModel, name: str, loop: str, batch: list[MotionRequest], progress: Progress) -> list[dict]:
    config = PlannerConfig(collision_model="exact" if loop.endswith("exact checker") else "spheres")
    planner = MotionPlanner.from_scene(robot, Scene.from_yaml(PROBLEMS[name].scene_path), config)
    python_loop = mock.patch.object(RCRRT, "compiled", property(lambda _self: False))
    with python_loop if loop != "compiled" else contextlib.nullcontext():
        planner.plan(batch[0])  # warm: numba loads its cached code, the scene's tables are built
        rows = []
        for request in batch:
            result = planner.plan(request)
            st = result.stats
            rows.append({"seed": request.seed, "success": result.success, "status": result.status.value,
                         "solve_s": st.solve_time, "total_s": st.total_time, "nodes": st.nodes,
                         "checks": st.collision_checks})  # fmt: skip
            progress.step(f"{name} {loop} seed {request.seed}")
    return rows


def summarise(rows: list[dict]) -> dict:
    solved = [r for r in rows if r["success"]]

    def pick(key: str, q: float) -> float | None:
        return float(np.percentile([r[key] for r in solved], q)) if solved else None

    return {"n": len(rows), "solved": len(solved), "solve_median_s": pick("solve_s", 50),
            "solve_p95_s": pick("solve_s", 95), "total_median_s": pick("total_s", 50),
            "nodes_median": pick("nodes", 50), "checks_median": pick("checks", 50)}  # fmt: skip


def markdown(summary: dict, seeds: int) -> str:
    lines = ["# RC-RRT: compiled loop vs Python loop", "",
             f"`PlannerConfig()` requests, planner RCRRT, {seeds} seeds, {BUDGET:g} s budget. Search = the planner's "
             "solve; request = the whole `plan` call (validation, search, shortcut, toppra, certification).", "",
             "| problem | loop | solved | search median ms | search p95 ms | request median ms | nodes | checks |"
             " Python loop / compiled (search median) |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for name, loops in summary.items():
        base = loops["compiled"]["solve_median_s"]
        for loop, s in loops.items():
            ratio = f"{s['solve_median_s'] / base:.1f}×" if base and s["solve_median_s"] else "—"
            lines.append(f"| {name} | {loop} | {s['solved']}/{s['n']} | {_ms(s['solve_median_s'])} | "
                         f"{_ms(s['solve_p95_s'])} | {_ms(s['total_median_s'])} | {_n(s['nodes_median'])} | "
                         f"{_n(s['checks_median'])} | {ratio} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def _ms(seconds: float | None) -> str:
    return "—" if seconds is None else f"{1e3 * seconds:.1f}"


def _n(value: float | None) -> str:
    return "—" if value is None else f"{value:.0f}"


def plot(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    problems = list(results["runs"])
    fig, axes = plt.subplots(1, len(problems), figsize=(5 * len(problems), 4), squeeze=False)
    for ax, name in zip(axes[0], problems, strict=True):
        runs = results["runs"][name]
        data = [[1e3 * r["solve_s"] for r in runs[loop] if r["success"]] or [np.nan] for loop in LOOPS]
        ax.boxplot(data, showfliers=True)
        ax.set_xticks(range(1, len(LOOPS) + 1), [loop.replace(", ", "\n") for loop in LOOPS])
        if not all(np.isnan(d).all() for d in data):
            ax.set_yscale("log")
        ax.set_ylabel("search time per request (ms, log)")
        ax.set_title(f"RC-RRT on {name}")
        ax.grid(True, which="both", axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--quick", action="store_true", help="3 seeds")
    ap.add_argument("--out", type=Path, default=RESULTS / "rcrrt_loop")
    args = ap.parse_args(argv)
    seeds = 3 if args.quick else args.seeds
    if seeds < 1:
        ap.error("--seeds must be >= 1")
    log("loading Maru-1 ...")
    robot = RobotModel.maru1()
    problems = ("maru6", "maru13")
    progress = Progress(len(problems) * len(LOOPS) * seeds)
    results: dict = {"config": {"seeds": seeds, "budget_s": BUDGET}, "runs": {}}
    for name in problems:
        batch = requests(robot, name, seeds)
        results["runs"][name] = {loop: run_loop(robot, name, loop, batch, progress) for loop in LOOPS}
    summary = {name: {loop: summarise(rows) for loop, rows in loops.items()} for name, loops in results["runs"].items()}
    results["summary"] = summary
    write_results(args.out, results, markdown(summary, seeds), lambda path: plot(results, path), quick=args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
