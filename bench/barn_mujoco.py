"""The BARN Challenge in MuJoCo: our base stack on the 300 public worlds, scored like the challenge (issue 38).

    .venv/bin/python bench/barn_mujoco.py [--quick] [--trials 3] [--processes 2] [--world-step 1] [--no-kinematic]

In-process runs (the stack's core code, no DDS): no prior map, the challenge's start, goal, clock and metric
(clip 2-8). Beside them: the published DWA and DRL-VO figures and our 2-D kinematic simulator (paper 001's
reproduction: the elastic strip on the generator's path, a prior map, at 0.5 m/s) on the same worlds.
Writes bench/results/barn_mujoco.{json,md,png}; --quick: 6 worlds x 2 trials under bench/results/quick/.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from _common import Progress, data_dir, log, require_data, result_path, write_results

from maru_planner.barn.scoring import RunScore, barn_metric, summarise
from maru_planner.barn.stack import run_barn
from maru_planner.physics.barn_world import WORLD_COUNT, cylinder_centres, optimal_time, world_grid
from maru_planner.physics.base_sim import BaseSim

REPO = Path(__file__).resolve().parent.parent
QUICK_WORLDS = [0, 60, 120, 180, 240, 299]
# the-barn-challenge README (main) and its committed res/dwa_out.txt; DRL-VO: the 2022 winner (clip 4-8, max 0.25)
PUBLISHED = {
    "DWA (Gazebo, README)": {"success_rate": 0.88, "collision_rate": 0.048, "timeout_rate": 0.072, "metric": 0.1693},
    "DWA (Gazebo, res/dwa_out.txt)": {
        "success_rate": 0.85,
        "collision_rate": 0.056,
        "timeout_rate": 0.094,
        "metric": 0.1586,
    },
    "DRL-VO (Gazebo, 2022 winner)": {
        "success_rate": None,
        "collision_rate": None,
        "timeout_rate": None,
        "metric": 0.2339,
    },
}
PUBLISHED_NOTES = {
    "DWA (Gazebo, README)": "50 test worlds x 10; 0.1693 under the old clip 4-8",
    "DWA (Gazebo, res/dwa_out.txt)": "500 runs, recomputed with clip 2-8 (0.1575 with 4-8)",
    "DRL-VO (Gazebo, 2022 winner)": "competition score under the 2022 clip 4-8 (max 0.25)",
}


def _run_task(task: tuple[int, int]) -> tuple[dict, dict | None]:
    world, seed = task
    score, trace = run_barn(world_grid(world), optimal_time(world), seed=seed, world_name=str(world))
    picture = None
    if seed == 0:
        picture = {"trajectory": trace.trajectory[::4], "global_path": trace.global_path, "contacts": trace.contacts}
    return score.to_json(), picture


def _kinematic_task(world: int) -> dict:
    from paper001 import barn_run, barn_world  # lazy: a bench script, only for the kinematic peer

    sim_world, optimal = barn_world(world)
    result = barn_run(sim_world, "modified")
    return {
        "world": str(world),
        "success": result.success,
        "collision": result.outcome == "collision",
        "timeout": result.outcome == "timeout",
        "metric": barn_metric(result.success, result.time_to_goal, optimal),
    }


def physics_realtime_factor(seconds: float = 20.0) -> float:
    """Physics + the laser at 50 Hz alone (no stack), world 0, the robot driving."""
    sim = BaseSim(world_grid(0))
    wall = time.perf_counter()
    for _ in range(round(seconds / 0.05)):
        sim.command(0.3, 0.2)
        sim.advance(0.05)
    return seconds / (time.perf_counter() - wall)


def _pool_map(func, tasks: list, workers: int, label) -> list:
    progress = Progress(len(tasks))
    out = []
    if workers == 1:  # one process: no pool, the runs in this process
        for task in tasks:
            out.append(func(task))
            progress.step(label(out[-1]))
        return out
    with get_context("spawn").Pool(workers) as pool:
        for item in pool.imap_unordered(func, tasks):
            out.append(item)
            progress.step(label(item))
    return out


def kinematic_summary(records: list[dict]) -> dict:
    n = len(records)
    return {
        "worlds": n,
        "runs": n,
        "success_rate": round(sum(r["success"] for r in records) / n, 4),
        "collision_rate": round(sum(r["collision"] for r in records) / n, 4),
        "timeout_rate": round(sum(r["timeout"] for r in records) / n, 4),
        "mean_metric": round(float(np.mean([r["metric"] for r in records])), 4),
    }


def targets(ours: dict) -> list[dict]:
    return [
        {"target": "success >= 95 %", "hit": ours["success_rate"] >= 0.95, "measured": ours["success_rate"]},
        {"target": "collisions <= 2 %", "hit": ours["collision_rate"] <= 0.02, "measured": ours["collision_rate"]},
        {
            "target": "mean metric >= 0.30 (clip 2-8)",
            "hit": ours["mean_metric"] >= 0.30,
            "measured": ours["mean_metric"],
        },
        {
            "target": "in-process >= 10x real time (wall clock, per worker process)",
            "hit": (ours["realtime_factor"] or 0) >= 10,
            "measured": f"{ours['realtime_factor']} wall, {ours['realtime_factor_cpu']} per CPU second "
            f"(machine load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)",
        },
    ]


def markdown(meta: dict, summary: dict, kin: dict | None, hits: list[dict], failures: list[dict]) -> str:
    ours = summary["in_process"]
    lines = [
        "# BARN in MuJoCo (issue 38)",
        "",
        f"Command: `{meta['command']}`; {ours['worlds']} worlds x {meta['trials']} trials, {meta['workers']} "
        f"processes, wall {meta['wall_time_s']} s, load average {meta.get('load_average', '?')} (1 min, "
        "start / end: the wall-clock real-time factor is per process and falls with the load). "
        f"Physics {meta['timestep_s']} s, laser 720 beams (UST-10-like), "
        "no prior map. Metric = success x OT / clip(T, 2 OT, 8 OT).",
        "",
        "| planner | worlds x runs | success | collision | timeout | metric | note |",
        "|---|---|---|---|---|---|---|",
        f"| **ours, MuJoCo in-process** | {ours['worlds']} x {meta['trials']} | {ours['success_rate']:.3f} | "
        f"{ours['collision_rate']:.3f} | {ours['timeout_rate']:.3f} | **{ours['mean_metric']:.4f}** | "
        f"mean T {ours['mean_time_s']} s; {ours['realtime_factor']}x real time (wall), "
        f"{ours['realtime_factor_cpu']}x per CPU second |",
    ]
    if kin is not None:
        lines.append(
            f"| ours, 2-D kinematic sim (paper 001) | {kin['worlds']} x 1 | {kin['success_rate']:.3f} | "
            f"{kin['collision_rate']:.3f} | {kin['timeout_rate']:.3f} | {kin['mean_metric']:.4f} | "
            "generator's path given (prior map), 0.5 m/s |"
        )
    ros = summary.get("through_ros")
    if ros:
        lines.append(
            f"| ours, MuJoCo through ROS (4 processes, lock-step) | {ros['worlds']} x 1 "
            f"(of {ros.get('planned_worlds', ros['worlds'])}) | {ros['success_rate']:.3f} | "
            f"{ros['collision_rate']:.3f} | {ros['timeout_rate']:.3f} | {ros['mean_metric']:.4f} | "
            f"the challenge's test worlds (0, 6, ...); {ros['realtime_factor']}x real time "
            f"(wall, load {ros['load_average']}); "
            f"{ros['errors']} runs not carried out |"
        )
    for name, values in PUBLISHED.items():
        cells = [
            f"{values[k]:.3f}" if values[k] is not None else "-"
            for k in ("success_rate", "collision_rate", "timeout_rate")
        ]
        lines.append(f"| {name} | 50 x 10 | {' | '.join(cells)} | {values['metric']:.4f} | {PUBLISHED_NOTES[name]} |")
    lines += ["", f"Physics + laser alone: {meta['physics_realtime_factor']}x real time.", "", "## Targets", ""]
    lines += [f"- {'HIT' if t['hit'] else 'MISS'}: {t['target']} - measured {t['measured']}" for t in hits]
    lines += ["", "## Failed runs", ""]
    lines += [
        f"- world {f['world']} seed {f['seed']}: {'collision' if f['collision'] else 'timeout'}" for f in failures
    ]
    if not failures:
        lines.append("- none")
    if not ros:
        lines += [
            "",
            "Not run here: the through-ROS half (`summary.through_ros`): `bench/barn_mujoco.py --through-ros`.",
        ]
    return "\n".join(lines) + "\n"


def plot(path: Path, summary: dict, kin: dict | None, pictures: dict[str, dict]) -> None:
    # lazy: matplotlib only when writing the figure
    import matplotlib.pyplot as plt

    from maru_planner.viz.barn import draw_barn_run

    shown = sorted(pictures, key=lambda w: (pictures[w]["failed"] is False, int(w)))[:5]
    fig = plt.figure(figsize=(14, 6))
    ax = fig.add_subplot(1, 1 + len(shown), 1)
    names = ["ours\nMuJoCo"] + (["ours\n2-D"] if kin else []) + ["DWA\nREADME", "DWA\nlog", "DRL-VO"]
    metrics = [summary["in_process"]["mean_metric"]] + ([kin["mean_metric"]] if kin else [])
    metrics += [v["metric"] for v in PUBLISHED.values()]
    ax.bar(range(len(names)), metrics, color=["tab:blue"] + (["tab:cyan"] if kin else []) + ["tab:gray"] * 3)
    ax.axhline(0.30, ls="--", color="tab:green", lw=1)
    ax.set_xticks(range(len(names)), names, fontsize=7)
    ax.set_ylabel("mean BARN metric")
    ax.set_title("metric (clip 2-8; DRL-VO, DWA README: 4-8)", fontsize=8)
    for i, world in enumerate(shown):
        pic = pictures[world]
        draw_barn_run(
            fig.add_subplot(1, 1 + len(shown), 2 + i),
            cylinder_centres(world_grid(int(world))),
            pic["trajectory"],
            pic["global_path"],
            pic["contacts"],
            title=f"world {world}: {pic['title']}",
        )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=f"worlds {QUICK_WORLDS} x 2 trials")
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--processes", "--workers", dest="workers", type=int, default=2, choices=(1, 2))
    parser.add_argument("--world-step", type=int, default=1)
    parser.add_argument("--no-kinematic", action="store_true", help="skip the 2-D kinematic simulator peer")
    parser.add_argument("--through-ros", action="store_true", help="only the 50 test worlds x 1 through ROS, merged")
    parser.add_argument("--combine", action="store_true", help="only merge <out>_through_ros.json into <out>.json")
    parser.add_argument("--out", default=str(REPO / "bench" / "results" / "barn_mujoco"))
    args = parser.parse_args(argv)
    require_data(data_dir("barn", "grid_files"))
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    if args.through_ros or args.combine:
        return through_ros_main(args)
    worlds = QUICK_WORLDS if args.quick else list(range(0, WORLD_COUNT, args.world_step))
    trials = 2 if args.quick else args.trials
    t0 = time.time()
    load_start = round(os.getloadavg()[0], 1)
    physics_rtf = round(physics_realtime_factor(), 2)
    log(f"physics + laser alone: {physics_rtf}x real time")
    tasks = [(w, s) for w in worlds for s in range(trials)]
    results = _pool_map(_run_task, tasks, args.workers, lambda item: f"world {item[0]['world']} seed {item[0]['seed']}")
    runs = sorted((RunScore(**r) for r, _ in results), key=lambda r: (int(r.world), r.seed))
    summary = {"in_process": summarise(runs), "through_ros": None}
    kin = None
    if not args.no_kinematic:
        kin_records = _pool_map(_kinematic_task, worlds, args.workers, lambda item: f"kinematic world {item['world']}")
        kin = kinematic_summary(kin_records)
        summary["kinematic_2d"] = kin
    summary["published"] = PUBLISHED
    by_world = {r.world: r for r in runs if r.seed == 0}
    pictures = {}
    for record, picture in results:
        if picture is not None:
            run = by_world[record["world"]]
            outcome = "success" if run.success else "collision" if run.collision else "timeout"
            pictures[record["world"]] = {**picture, "failed": not run.success, "title": f"{outcome} {run.metric:.3f}"}
    failures = [r.to_json() for r in runs if not r.success]
    meta = {
        "command": "bench/barn_mujoco.py" + (" --quick" if args.quick else ""),
        "trials": trials,
        "workers": args.workers,
        "timestep_s": 0.005,
        "physics_realtime_factor": physics_rtf,
        "wall_time_s": round(time.time() - t0, 1),
        "load_average": f"{load_start} / {round(os.getloadavg()[0], 1)}",
    }
    hits = targets(summary["in_process"])
    payload = {"meta": meta, "summary": summary, "targets": hits, "runs": [r.to_json() for r in runs]}
    write_results(
        Path(args.out),
        payload,
        markdown(meta, summary, kin, hits, failures),
        lambda path: plot(path, summary, kin, pictures),
        quick=args.quick,
    )
    return 0


def through_ros_main(args: argparse.Namespace) -> int:
    """--through-ros: run the test worlds through ROS into <out>_through_ros.json; then (and --combine) merge it
    into <out>.json and rewrite <out>.md (the figure stays the in-process run's)."""
    import barn_through_ros  # lazy: a bench module beside this one, only for the through-ROS half

    out = result_path(Path(args.out), args.quick)
    ros_path = out.parent / f"{out.name}_through_ros.json"
    if args.through_ros:
        worlds = barn_through_ros.QUICK_TEST_WORLDS if args.quick else barn_through_ros.TEST_WORLDS
        ros_path.parent.mkdir(parents=True, exist_ok=True)
        ros = barn_through_ros.through_ros(worlds, ros_path)
        ros_path.write_text(json.dumps(ros, indent=1))
        log(f"wrote {ros_path}: {ros['summary']}")
    main_json = out.with_suffix(".json")
    if not main_json.is_file() or not ros_path.is_file():
        log(f"nothing merged: {main_json} or {ros_path} is missing")
        return 0
    results = barn_through_ros.merge(json.loads(main_json.read_text()), json.loads(ros_path.read_text()))
    main_json.write_text(json.dumps(results, indent=1))
    summary, runs = results["summary"], [RunScore(**r) for r in results["runs"]]
    failures = [r.to_json() for r in runs if not r.success]
    text = markdown(results["meta"], summary, summary.get("kinematic_2d"), results["targets"], failures)
    out.with_suffix(".md").write_text(text)
    print(text)
    log(f"merged summary.through_ros into {main_json} and {out.with_suffix('.md')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
