"""Paper 004 benchmark: track following vs virtual wall on the biped scenes, beside the paper's Table 1.

    .venv/bin/python bench/paper004.py [--quick]

Each scene in config/worlds/biped/ is mapped 3-D → 2-D and both planners run
``repeats`` times (median time). A 2-D A* for a wheeled robot with the same
body (a disc of radius w_r/2, every obstacle under the robot's height) runs
beside them: it shows what the 3-D → 2-D mapping buys.
Writes bench/results/paper004.{json,md,png} (+ one picture per scene).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import results_dir  # noqa: E402

from maru_planner.base.astar import astar_2d  # noqa: E402
from maru_planner.base.biped import (  # noqa: E402
    TrackFollowingPlanner,
    VirtualWallPlanner,
    load_world,
    map_3d_to_2d,
    wheeled_map,
)
from maru_planner.base.grid import OccupancyGrid  # noqa: E402

RESULTS = ROOT / "bench" / "results"
WORLDS = ROOT / "config" / "worlds" / "biped"
PAPER = {
    "biped_track": {"time": 0.01, "K<L": True, "K>L": False},
    "biped_wall": {"time": 0.901, "K<L": True, "K>L": True},
}


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def timed(fn, repeats: int):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def run_scene(path: Path, repeats: int) -> tuple[list, dict]:
    world = load_world(path)
    m, map_time = timed(lambda: map_3d_to_2d(world), repeats)
    k, half = world.robot.corner_distance, None
    rows, plans = [], {}
    for name, cls in (("biped_track", TrackFollowingPlanner), ("biped_wall", VirtualWallPlanner)):
        plan, elapsed = timed(lambda cls=cls: cls(world.robot).plan(m, world.start, world.goal), repeats)
        plans[name] = plan
        rows.append(
            {
                "scene": world.name,
                "planner": name,
                "success": plan.success,
                "time": elapsed,
                "map_time": map_time,
                "length": plan.path_length(),
                "steps": len(plan.path),
                "collision_checks": plan.stats.collision_checks,
                "message": plan.message,
            }
        )
    grid = OccupancyGrid(wheeled_map(world), world.resolution, (world.bounds[0], world.bounds[1], 0.0))
    grown = grid.inflate(world.robot.body_width / 2).occupied
    s, g = grid.world_to_cell(*world.start[:2]), grid.world_to_cell(*world.goal[:2])
    free_ends = not grown[s] and not grown[g]
    out, elapsed = timed(lambda: astar_2d(grown, s, g) if free_ends else None, repeats)
    rows.append(
        {
            "scene": world.name,
            "planner": "wheeled_astar",
            "success": bool(out is not None and len(out.path)),
            "time": elapsed,
            "map_time": 0.0,
            "length": float(out.cost * world.resolution) if out is not None and len(out.path) else 0.0,
            "steps": int(len(out.path)) if out is not None else 0,
            "collision_checks": None,
            "message": "disc of radius w_r/2 among all obstacles" + ("" if free_ends else "; start/goal blocked"),
        }
    )
    half = min(np.max(m.clearance()), 9.9)
    info = {"K": k, "description": world.meta.get("description", ""), "max_clearance": float(half)}
    from maru_planner.viz.biped import save_scene_png

    save_scene_png(
        RESULTS / f"paper004_{world.name}.png", world, m, plans, f"{world.name}: K = {k:.3f} m — {info['description']}"
    )
    return rows, info


def table(rows: list) -> str:
    lines = ["| scene | planner | ok | time [s] | paper time [s] | path [m] | poses | note |", "|" + "---|" * 8]
    for r in rows:
        paper = PAPER.get(r["planner"], {}).get("time")
        lines.append(
            f"| {r['scene']} | {r['planner']} | {'yes' if r['success'] else 'NO'} | {r['time']:.4f} | "
            f"{paper if paper is not None else '—'} | {r['length']:.2f} | {r['steps']} | "
            f"{r['message'][:80]} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="one repetition")
    args = parser.parse_args(argv)
    global RESULTS
    RESULTS = results_dir(args.quick)  # --quick: bench/results/quick/, never the committed results
    RESULTS.mkdir(parents=True, exist_ok=True)
    repeats = 1 if args.quick else 5
    astar_2d(np.zeros((3, 3), bool), (0, 0), (2, 2))
    rows, scenes = [], {}
    for path in sorted(WORLDS.glob("*.yaml")):
        log(f"scene {path.stem} ...")
        scene_rows, info = run_scene(path, repeats)
        rows += scene_rows
        scenes[path.stem] = info
    (RESULTS / "paper004.json").write_text(
        json.dumps(
            {"quick": args.quick, "paper_table1": PAPER, "scenes": scenes, "results": rows}, indent=1, default=float
        )
    )
    md = [
        "# paper 004: biped planners vs the paper's Table 1",
        "",
        "Paper (Pentium 133 MHz): track following 0.01 s, virtual wall 0.901 s; K < L: both find a path; "
        "K > L: only the virtual wall.",
        "",
        table(rows),
        "",
    ]
    (RESULTS / "paper004.md").write_text("\n".join(md))
    _summary_png(rows)
    print(table(rows))
    return 0


def _summary_png(rows: list) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = sorted({r["scene"] for r in rows})
    planners = ["biped_track", "biped_wall", "wheeled_astar"]
    fig, ax = plt.subplots(figsize=(8, 4))
    width = 0.25
    for i, planner in enumerate(planners):
        vals = [next((r["time"] for r in rows if r["scene"] == s and r["planner"] == planner), 0) for s in scenes]
        ok = [next((r["success"] for r in rows if r["scene"] == s and r["planner"] == planner), False) for s in scenes]
        bars = ax.bar(np.arange(len(scenes)) + (i - 1) * width, vals, width, label=planner)
        for bar, success in zip(bars, ok):
            ax.text(
                bar.get_x() + bar.get_width() / 2,
                bar.get_height(),
                "ok" if success else "fail",
                ha="center",
                va="bottom",
                fontsize=8,
            )
    for planner, style in (("biped_track", "g--"), ("biped_wall", "r--")):
        ax.axhline(PAPER[planner]["time"], color=style[0], ls="--", lw=0.8, label=f"paper {planner}")
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(scenes)), scenes)
    ax.set_ylabel("planning time [s]")
    ax.legend(fontsize=8)
    ax.set_title("paper 004: biped planners (ok/fail above the bars) vs Table 1")
    fig.tight_layout()
    fig.savefig(RESULTS / "paper004.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
