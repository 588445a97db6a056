"""toppra's own driver against ours: time-optimal profiles of planned paths, the same stage programs (issue 16).

    .venv/bin/python bench/toppra_driver.py [--seeds 30] [--per-set 10] [--repeats 5] [--quick]

Paths: the Maru-1 13-DOF problem (``--seeds`` seeds) and ``--per-set`` MotionBenchMaker Panda problems per set,
planned as ``bench/peers_arm.py``'s "ours-compiled" (``CompiledRRTConnect`` on the sphere checker, 0.05 rad, no
simplification). Each path's corners are blended at the planner's ``blend_deviation`` (all blends as if certified)
and cut into sections at near reversals, as :func:`maru_planner.trajectory.parameterize` does; then for every
section, on the same grid and the same joint velocity and acceleration constraints:

- toppra's driver: ``toppra.algorithm.TOPPRA(..., solver_wrapper="seidel").compute_parameterization(0, 0)``
  (the baseline: what the toppra timing called before);
- ours: ``trajectory.toppra.rest_to_rest_speeds``, the same programs solved in closed form in one numba call
  (:mod:`maru_planner.trajectory.toppra_kernel`; what the toppra timing calls now).

Both times include evaluating the path on the grid (toppra's: building its LP wrapper); the constraint objects are
built once per path, outside the time. Each is the best of ``--repeats`` alternating runs. Reported per family:
paths, grid points, median time per path for each, the ratio, and the largest difference of the two profiles'
path speeds relative to their peak (toppra rounds its velocity bound on ṡ to single precision: ~1e-7).
Writes bench/results/toppra_driver.{json,md,png}.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import toppra.algorithm
import toppra.constraint

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import RESULTS, Progress, data_dir, log, require_data, write_results  # noqa: E402

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN, mbm_panda  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402
from maru_planner.scene.motion_bench_maker import iter_mbm_problems  # noqa: E402
from maru_planner.trajectory import Limits  # noqa: E402
from maru_planner.trajectory.blends import BlendedPath, blend_half_lengths, distinct, sections  # noqa: E402
from maru_planner.trajectory.toppra import rest_to_rest_speeds  # noqa: E402

DRIVERS = ("toppra's driver", "ours")
TARBALL = data_dir("motionbenchmaker", "vamp_panda_problems.tar.bz2")
CONFIG = PlannerConfig(collision_model="spheres", resolution=0.05)


def maru13_cases(robot: RobotModel, seeds: int) -> list[tuple[Scene, MotionRequest]]:
    problem = PROBLEMS["maru13"]
    names, scene = robot.groups[problem.group], Scene.from_yaml(problem.scene_path)
    return [(scene, MotionRequest(problem.group, start=problem.start_dict(names), goal_joints=problem.goal_dict(names),
                                  planner_id="CompiledRRTConnect", time_budget=1.0, seed=seed, simplify=False))
            for seed in range(seeds)]  # fmt: skip


def mbm_problem_cases(robot: RobotModel, per_set: int) -> list[tuple[Scene, MotionRequest]]:
    arm = set(robot.groups["arm"])
    problems = iter_mbm_problems(TARBALL, limit_per_set=per_set, fixed_joints=PANDA_FINGERS_OPEN)
    return [(p.scene, MotionRequest("arm", start=p.request.start, planner_id="CompiledRRTConnect",
                                    goal_joints={k: v for k, v in p.request.goal.items() if k in arm},
                                    time_budget=1.0, seed=0, simplify=False)) for p in problems]  # fmt: skip


def planned_paths(robot: RobotModel, cases: list[tuple[Scene, MotionRequest]], progress: Progress) -> list[dict]:
    """Each solved case's path (group waypoints) with its group's velocity and acceleration limits."""
    planner = MotionPlanner.from_scene(robot, None, CONFIG)
    out = []
    for scene, request in cases:
        planner.set_scene(scene)
        result = planner.plan(request)
        progress.step(f"planned {len(out) + 1}")
        if result.success:
            indices = robot.joint_indices(result.joint_names)
            out.append({"path": result.path, "velocity": np.asarray(robot.velocity_limits)[indices],
                        "acceleration": np.asarray(robot.acceleration_limits)[indices]})  # fmt: skip
    return out


def blended_sections(path: np.ndarray) -> list[BlendedPath]:
    waypoints = distinct(np.asarray(path, float))
    half = blend_half_lengths(waypoints, np.full(len(waypoints), CONFIG.blend_deviation))
    return [BlendedPath(w, h) for w, h in sections(waypoints, half)]


def toppras_driver(constraints: list, path: BlendedPath, grid: np.ndarray) -> np.ndarray | None:
    instance = toppra.algorithm.TOPPRA(constraints, path, gridpoints=grid, solver_wrapper="seidel")
    return instance.compute_parameterization(0.0, 0.0)[1]


def measure(item: dict, repeats: int) -> dict:
    """Both drivers on every section of one path: best-of-``repeats`` seconds summed over sections, grid points,
    and the largest speed difference relative to the profile's peak."""
    constraints = [toppra.constraint.JointVelocityConstraint(item["velocity"]),
                   toppra.constraint.JointAccelerationConstraint(item["acceleration"])]  # fmt: skip
    limits = Limits.scaled(item["velocity"], item["acceleration"])
    drivers = (lambda path, grid: toppras_driver(constraints, path, grid),
               lambda path, grid: rest_to_rest_speeds(path, grid, limits))  # fmt: skip
    seconds = dict.fromkeys(DRIVERS, 0.0)
    points, difference = 0, 0.0
    for path in blended_sections(item["path"]):
        grid, _ = path.grid()
        points += len(grid)
        best = dict.fromkeys(DRIVERS, np.inf)
        speeds = {}
        for _ in range(repeats):
            for name, driver in zip(DRIVERS, drivers, strict=True):
                t0 = time.perf_counter()
                speeds[name] = driver(path, grid)
                best[name] = min(best[name], time.perf_counter() - t0)
        for name in DRIVERS:
            seconds[name] += best[name]
        theirs, mine = speeds["toppra's driver"], speeds["ours"]
        if theirs is None or mine is None:
            difference = np.inf if (theirs is None) != (mine is None) else difference
            continue
        difference = max(difference, float(np.max(np.abs(mine - theirs)) / max(np.max(theirs), 1e-12)))
    return {"seconds": seconds, "grid_points": points, "relative_difference": difference}


def summarise(rows: list[dict]) -> dict:
    medians = {name: float(np.median([r["seconds"][name] for r in rows])) for name in DRIVERS}
    return {"paths": len(rows), "grid_points_median": float(np.median([r["grid_points"] for r in rows])),
            "median_s": medians, "ratio": medians["toppra's driver"] / medians["ours"],
            "max_relative_difference": max(r["relative_difference"] for r in rows)}  # fmt: skip


def markdown(summary: dict, args: argparse.Namespace) -> str:
    lines = ["# toppra's driver vs ours (the same stage programs, ours in closed form)", "",
             f"Paths planned by `CompiledRRTConnect` (0.05 rad, unsimplified), corners blended at "
             f"{CONFIG.blend_deviation:g} rad, sections cut at near reversals; time per path = sum over its sections "
             f"of the best of {args.repeats} runs, evaluating the path on the grid included. toppra rounds its "
             f"velocity bound on the path speed to single precision (~1e-7 of the peak).", "",
             "| paths | n | grid points (median) | toppra's driver, median ms | ours, median ms | toppra's / ours "
             "| largest speed difference (of peak) |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for family, s in summary.items():
        lines.append(f"| {family} | {s['paths']} | {s['grid_points_median']:.0f} | "
                     f"{1e3 * s['median_s'][DRIVERS[0]]:.2f} | {1e3 * s['median_s'][DRIVERS[1]]:.2f} | "
                     f"{s['ratio']:.1f}× | {s['max_relative_difference']:.1e} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def plot(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 5))
    top = 0.0
    for family, rows in results["runs"].items():
        x = [1e3 * r["seconds"][DRIVERS[0]] for r in rows]
        y = [1e3 * r["seconds"][DRIVERS[1]] for r in rows]
        ax.scatter(x, y, s=12, label=f"{family} ({len(rows)} paths)")
        top = max(top, *x, *y)
    ax.plot([0.05, top], [0.05, top], "k--", lw=0.8, label="equal time")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("toppra's driver: ms per path (log)")
    ax.set_ylabel("ours: ms per path (log)")
    ax.set_title("Time-optimal profile, same stage programs")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=30, help="Maru-1 13-DOF seeds")
    ap.add_argument("--per-set", type=int, default=10, help="MotionBenchMaker problems per set")
    ap.add_argument("--repeats", type=int, default=5, help="runs per section and driver (the best is kept)")
    ap.add_argument("--quick", action="store_true", help="3 seeds, 2 problems per set, 2 repeats")
    ap.add_argument("--out", type=Path, default=RESULTS / "toppra_driver")
    args = ap.parse_args(argv)
    require_data(TARBALL)
    if args.quick:
        args.seeds, args.per_set, args.repeats = 3, 2, 2
    if min(args.seeds, args.per_set, args.repeats) < 1:
        ap.error("--seeds, --per-set and --repeats must be >= 1")
    log("loading robots and problems ...")
    maru, panda = RobotModel.maru1(), mbm_panda()
    maru_cases, mbm_cases = maru13_cases(maru, args.seeds), mbm_problem_cases(panda, args.per_set)
    progress = Progress(len(maru_cases) + len(mbm_cases))
    paths = {"maru13": planned_paths(maru, maru_cases, progress), "mbm": planned_paths(panda, mbm_cases, progress)}
    results: dict = {"config": vars(args) | {"out": str(args.out)}, "runs": {}}
    progress = Progress(sum(len(items) for items in paths.values()))
    for family, items in paths.items():
        results["runs"][family] = []
        for item in items:
            results["runs"][family].append(measure(item, args.repeats))
            progress.step(f"{family} path {len(results['runs'][family])}")
    summary = {family: summarise(rows) for family, rows in results["runs"].items() if rows}
    results["summary"] = summary
    write_results(args.out, results, markdown(summary, args), lambda png: plot(results, png), quick=args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
