"""Scenes of many obstacles: build, check and plan time against the plain scene (issue 16 "scale of the scene").

    .venv/bin/python bench/scene_scale.py                          # 1,000 / 10,000 / 100,000 far + clutter
    .venv/bin/python bench/scene_scale.py --sizes 100 1000 --clutter 500 --seeds 2    # a quick smoke run

Robot and problem: Maru-1's 13-DOF paper problem (``maru13``: desk + box). Scenes:

- ``far N``: the problem's scene plus N small boxes, spheres and cylinders 2 to 20 robot reaches away
  in every direction (e.g. a building's map loaded as obstacles): they should cost almost nothing;
- ``clutter N``: the problem's scene plus N 1 cm spheres spread over the desk's and the box's top faces and
  a wall behind the robot, like a depth camera's point cloud of them, less the points within 5 cm of the
  robot at the start or the goal (a perception pipeline's robot self-filter; the paper's start has the
  hand 3 mm above the desk, where unfiltered points would leave no room for the safety margin).

Per scene: ``scene`` = ``Scene.from_dict`` (validation of every obstacle), ``exact build`` /
``spheres build`` = the checkers' build (reach culling, AABB tree / grid), ``exact check`` /
``spheres check`` = mean time per state over random configurations (the spheres checker in batches
of 32 states, as an edge check), ``plan exact`` / ``plan spheres`` = median ``MotionPlanner.plan``
wall time (RRTConnect, exact certification included) over the seeds, and each plan time's ratio to
the plain scene's (issue 16 target: 100,000 far obstacles add <= 20 %).
Writes bench/results/scene_scale.{json,md,png}.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import output_dir  # noqa: E402

from maru_planner.collision import CollisionChecker, SphereCollisionChecker  # noqa: E402
from maru_planner.collision.broadphase import robot_reach  # noqa: E402
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402

RESULTS = ROOT / "bench" / "results"
PROBLEM = PROBLEMS["maru13"]
STATES = 2000
BATCH = 32
SELF_FILTER = 0.05  # m: clutter points this close to the robot at the start or goal are dropped


def far_obstacles(rng: np.random.Generator, n: int, reach: float) -> list[dict]:
    """``n`` small primitives 2 to 20 reaches from the root, in every direction."""
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    centres = direction * rng.uniform(2 * reach, 20 * reach, (n, 1))
    sizes = rng.uniform(0.05, 0.5, (n, 3))
    out = []
    for i, (c, s) in enumerate(zip(centres.tolist(), sizes.tolist())):
        pose = {"xyz": c, "rpy": rng.uniform(-np.pi, np.pi, 3).tolist()}
        kind = i % 3
        if kind == 0:
            out.append({"name": f"far{i}", "type": "box", "size": s, "pose": pose})
        elif kind == 1:
            out.append({"name": f"far{i}", "type": "sphere", "radius": s[0] / 2, "pose": pose})
        else:
            out.append({"name": f"far{i}", "type": "cylinder", "radius": s[0] / 2, "length": s[1], "pose": pose})
    return out


def surface_points(rng: np.random.Generator, n: int, obstacle: dict) -> np.ndarray:
    """``n`` points on the top face of a box obstacle dict (its pose has no rotation in the paper scenes)."""
    size = np.asarray(obstacle["size"], dtype=float)
    centre = np.asarray(obstacle["pose"]["xyz"], dtype=float)
    top = centre + [0.0, 0.0, size[2] / 2 + 0.01]
    return top + rng.uniform(-0.5, 0.5, (n, 2)) @ np.diag(size[:2]) @ np.eye(2, 3)


def clutter_obstacles(rng: np.random.Generator, n: int, base: dict) -> list[dict]:
    """``n`` 1 cm spheres, evenly spread (per area) over the top faces of the scene's boxes and a wall behind
    the robot, like a depth camera's point cloud of them."""
    boxes = [o for o in base["obstacles"] if o["type"] == "box"]
    wall_area = 2.4 * 2.0
    areas = np.array([o["size"][0] * o["size"][1] for o in boxes] + [wall_area])
    counts = rng.multinomial(n, areas / areas.sum())
    on_boxes = [surface_points(rng, int(k), box) for k, box in zip(counts[:-1], boxes)]
    wall = rng.uniform([-0.7, -1.2, -1.0], [-0.68, 1.2, 1.0], (int(counts[-1]), 3))
    points = np.concatenate([*on_boxes, wall])
    return [{"name": f"pt{i}", "type": "sphere", "radius": 0.01, "pose": {"xyz": p}} for i, p in
            enumerate(points.tolist())]  # fmt: skip


def self_filtered(robot: RobotModel, entries: list[dict], configurations: list[np.ndarray]) -> list[dict]:
    """``entries`` without the points within :data:`SELF_FILTER` of the robot at any of ``configurations``."""
    checker = CollisionChecker(robot, Scene.from_dict({"obstacles": entries}), padding=SELF_FILTER)
    close = {name for q in configurations for pair in checker.colliding_pairs(q) for name in pair}
    return [entry for entry in entries if entry["name"] not in close]


def problem_ends(robot: RobotModel) -> list[np.ndarray]:
    """The paper problem's start and goal as full configurations."""
    names = robot.groups[PROBLEM.group]
    ends = []
    for values in (PROBLEM.start_dict(names), PROBLEM.goal_dict(names)):
        q = np.asarray(robot.neutral(), dtype=float).copy()
        q[robot.joint_indices(list(values))] = list(values.values())
        ends.append(q)
    return ends


def time_checks(robot: RobotModel, scene: Scene, Q: np.ndarray) -> dict:
    t0 = time.perf_counter()
    exact = CollisionChecker(robot, scene)
    t1 = time.perf_counter()
    spheres = SphereCollisionChecker(robot, scene)
    t2 = time.perf_counter()
    exact_valid = exact.are_valid(Q)
    t3 = time.perf_counter()
    sphere_valid = np.concatenate([spheres.are_valid(Q[k : k + BATCH]) for k in range(0, len(Q), BATCH)])
    t4 = time.perf_counter()
    return {
        "exact_build_s": t1 - t0,
        "spheres_build_s": t2 - t1,
        "exact_check_us": (t3 - t2) / len(Q) * 1e6,
        "spheres_check_us": (t4 - t3) / len(Q) * 1e6,
        "agree": bool(np.array_equal(exact_valid, sphere_valid)),
        "exact_tree": exact.scene_tree is not None,
        "spheres_grid": spheres.uses_grid,
        "reachable": len(spheres.primitives.names),
    }


def time_plans(robot: RobotModel, scene: Scene, collision_model: str, seeds: int) -> dict:
    config = PlannerConfig(collision_model=collision_model)
    planner = MotionPlanner.from_scene(robot, scene, config)
    names = robot.groups[PROBLEM.group]
    times, solved = [], 0
    for seed in range(seeds):
        request = MotionRequest(PROBLEM.group, start=PROBLEM.start_dict(names), goal_joints=PROBLEM.goal_dict(names),
                                planner_id="RRTConnect", time_budget=10.0, seed=seed)  # fmt: skip
        t0 = time.perf_counter()
        result = planner.plan(request)
        times.append(time.perf_counter() - t0)
        solved += bool(result.success)
    return {"median_s": float(np.median(times)), "solved": solved, "runs": seeds}


def run_case(robot, label: str, entries: list[dict], Q: np.ndarray, seeds: int) -> dict:
    t0 = time.perf_counter()
    scene = Scene.from_dict({"obstacles": entries})
    row = {"scene": label, "obstacles": len(entries), "scene_s": time.perf_counter() - t0}
    row.update(time_checks(robot, scene, Q))
    for model in ("exact", "spheres"):
        row[f"plan_{model}"] = time_plans(robot, scene, model, seeds)
    print(f"  {label:>14}: " + ", ".join(f"{k}={v}" for k, v in row.items() if k not in ("scene",)), flush=True)
    return row


def add_ratios(rows: list[dict]) -> None:
    base = rows[0]
    for row in rows:
        for model in ("exact", "spheres"):
            row[f"plan_{model}"]["ratio"] = row[f"plan_{model}"]["median_s"] / base[f"plan_{model}"]["median_s"]


def markdown(rows: list[dict], meta: dict) -> str:
    head = ("| scene | obstacles | kept | scene [s] | exact build [s] | spheres build [s] | exact check [µs] "
            "| spheres check [µs] | plan exact [ms] (× plain) | plan spheres [ms] (× plain) | solved |")  # fmt: skip
    lines = [f"# Scene scale ({meta['date']}, {meta['machine']})", "",
             "Maru-1 13-DOF paper problem (desk + box) plus N obstacles; columns explained in bench/scene_scale.py.",
             "kept = obstacles within the robot's reach (the rest are dropped at build time).", "", head,
             "|" + "---|" * 11]  # fmt: skip
    for r in rows:
        pe, ps = r["plan_exact"], r["plan_spheres"]
        lines.append(
            f"| {r['scene']} | {r['obstacles']} | {r['reachable']} | {r['scene_s']:.3f} | {r['exact_build_s']:.3f} "
            f"| {r['spheres_build_s']:.3f} | {r['exact_check_us']:.1f} | {r['spheres_check_us']:.1f} "
            f"| {pe['median_s'] * 1e3:.1f} ({pe['ratio']:.2f}) | {ps['median_s'] * 1e3:.1f} ({ps['ratio']:.2f}) "
            f"| {pe['solved']}/{pe['runs']}, {ps['solved']}/{ps['runs']} |"
        )
    return "\n".join(lines) + "\n"


def plot(rows: list[dict], path: Path) -> None:
    labels = [r["scene"] for r in rows]
    x = np.arange(len(rows))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    panels = [
        ("build [s]", [("exact", "exact_build_s"), ("spheres", "spheres_build_s"), ("Scene.from_dict", "scene_s")]),
        ("check per state [µs]", [("exact", "exact_check_us"), ("spheres", "spheres_check_us")]),
        ("plan, median [ms]", [("exact", "plan_exact"), ("spheres", "plan_spheres")]),
    ]
    for ax, (title, series) in zip(axes, panels):
        width = 0.8 / len(series)
        for k, (name, key) in enumerate(series):
            values = [r[key]["median_s"] * 1e3 if isinstance(r[key], dict) else r[key] for r in rows]
            ax.bar(x + (k - (len(series) - 1) / 2) * width, values, width, label=name)
        ax.set_yscale("log")
        ax.set_xticks(x, labels, rotation=20)
        ax.set_title(title)
        ax.legend(fontsize=8)
    fig.suptitle("Maru-1 13-DOF paper problem: desk + box plus N obstacles")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000], help="far obstacle counts")
    parser.add_argument("--clutter", type=int, default=10000, help="clutter obstacles (0: none)")
    parser.add_argument("--seeds", type=int, default=5, help="plans per scene and checker")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    args.out = output_dir(args.out, args.quick)  # --quick: bench/results/quick/, never the committed results
    if min(args.sizes) < 0 or args.clutter < 0 or args.seeds < 1:
        print("scene_scale: sizes and --clutter must be >= 0 and --seeds >= 1", file=sys.stderr)
        return 2
    robot = RobotModel.maru1()
    rng = np.random.default_rng(0)
    Q = np.array([robot.random_configuration(rng) for _ in range(STATES)])
    base = Scene.from_yaml(PROBLEM.scene_path).to_dict()
    reach = robot_reach(robot)
    cases = [("plain", [])] + [(f"far {n:,}", far_obstacles(rng, n, reach)) for n in args.sizes]
    if args.clutter:
        clutter = self_filtered(robot, clutter_obstacles(rng, args.clutter, base), problem_ends(robot))
        cases.append((f"clutter {args.clutter:,}", clutter))
    print(f"Maru-1 {PROBLEM.name}, reach {reach:.2f} m, {STATES} states, {args.seeds} plans per scene and checker")
    plain = Scene.from_dict(base)
    time_checks(robot, plain, Q[:BATCH])  # warm-up (numba kernels loaded, caches filled): not reported
    for model in ("exact", "spheres"):
        time_plans(robot, plain, model, 1)
    rows = [run_case(robot, label, base["obstacles"] + extra, Q, args.seeds) for label, extra in cases]
    add_ratios(rows)
    meta = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "machine": platform.platform(),
            "python": sys.version.split()[0], "args": {k: str(v) for k, v in vars(args).items()}}  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "scene_scale.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=2))
    text = markdown(rows, meta)
    (args.out / "scene_scale.md").write_text(text)
    plot(rows, args.out / "scene_scale.png")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
