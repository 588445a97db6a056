"""Cost of a validity check: our CollisionChecker vs pinocchio.computeCollisions called naively.

    .venv/bin/python bench/collision.py [--quick]

Robots: Maru-1 13-DOF upper body in the paper's desk + box scene, and the
Panda (mesh collision model) beside a table with a box on it. Workloads:

- single states: uniform random configurations (a mix of valid and invalid);
- edges: pairs of random valid states 0.2-1.0 rad apart (RRT-like steps),
  discretised at 0.02 rad, each checked as one batch.

Methods:
- ``naive``: what a first Pinocchio script does: ``addAllCollisionPairs``
  minus the SRDF's disabled pairs, scene objects appended, then
  ``pin.computeCollisions(model, data, gmodel, gdata, q, False)`` per state
  (every pair, no early exit);
- ``naive+alloc``: the same with fresh Data/GeometryData for every call;
- ``ours is_valid``: ``CollisionChecker.is_valid`` (coal broad phase, stop at
  the first collision, buffers reused);
- ``ours pair loop``: the same checker with ``broadphase="none"`` (scene pairs
  first, stop at the first collision): what the broad phase buys;
- ``ours first_invalid`` / ``ours any_invalid``: batched edge check, sequential
  or in bisection order.

Every method's verdicts are compared with the naive check (must agree).
Writes bench/results/collision.{json,md,png}.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import results_dir  # noqa: E402

from maru_planner.collision import CollisionChecker  # noqa: E402
from maru_planner.paths import config_path  # noqa: E402
from maru_planner.robot import RobotModel, load_example_robot  # noqa: E402
from maru_planner.scene import Obstacle, Scene  # noqa: E402

RESULTS = ROOT / "bench" / "results"
EDGE_LENGTH = (0.2, 1.0)
REPEATS = 3  # each timing is the best of REPEATS runs (shared CPUs)
RESOLUTION = 0.02


def panda_scene() -> Scene:
    return Scene(
        [
            Obstacle("table", "box", size=(0.6, 1.0, 0.05), pose=[0.55, 0.0, 0.2]),
            Obstacle("box", "box", size=(0.15, 0.15, 0.3), pose=[0.5, 0.0, 0.375]),
            Obstacle("post", "cylinder", radius=0.05, length=1.0, pose=[0.0, 0.5, 0.5]),
        ]
    )


class NaiveChecker:
    """All pairs minus SRDF-disabled ones, every pair evaluated per state."""

    def __init__(self, robot: RobotModel, scene: Scene, allocate: bool):
        gm = robot.collision_model.copy()
        n_robot = gm.ngeoms
        for o in scene.obstacles.values():
            placement = pin.SE3(o.pose[:3, :3].copy(), o.pose[:3, 3].copy())
            gm.addGeometryObject(pin.GeometryObject(o.name, 0, 0, placement, o.geometry()))
        gm.addAllCollisionPairs()
        links = [robot.model.frames[g.parentFrame].name for g in gm.geometryObjects[:n_robot]]
        for k in reversed(range(len(gm.collisionPairs))):
            p = gm.collisionPairs[k]
            a, b = p.first, p.second
            same = gm.geometryObjects[a].parentJoint == gm.geometryObjects[b].parentJoint
            if a >= n_robot and b >= n_robot or same:
                gm.removeCollisionPair(p)
            elif a < n_robot and b < n_robot and frozenset((links[a], links[b])) in robot.srdf.disabled_pairs:
                gm.removeCollisionPair(p)
        self.robot, self.gm, self.allocate = robot, gm, allocate
        self.data, self.gdata = robot.model.createData(), pin.GeometryData(gm)
        self.n_pairs = len(gm.collisionPairs)

    def is_valid(self, q: np.ndarray) -> bool:
        if self.allocate:
            self.data, self.gdata = self.robot.model.createData(), pin.GeometryData(self.gm)
        return not pin.computeCollisions(self.robot.model, self.data, self.gm, self.gdata, q, False)


def make_edges(robot, checker, rng, n_edges):
    """Edges between valid states EDGE_LENGTH apart (joint-space norm), discretised at RESOLUTION."""
    edges = []
    while len(edges) < n_edges:
        a = robot.random_configuration(rng)
        if not checker.is_valid(a):
            continue
        d = rng.normal(size=robot.nq)
        step = rng.uniform(*EDGE_LENGTH)
        b = np.clip(a + step * d / np.linalg.norm(d), robot.lower_limits, robot.upper_limits)
        if not checker.is_valid(b):
            continue
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / RESOLUTION)) + 1)
        edges.append(np.linspace(a, b, n))
    return edges


def timed(fn, items):
    best = np.inf
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        out = [fn(x) for x in items]
        best = min(best, time.perf_counter() - t0)
    return best, out


def bench_robot(label, robot, scene, n_states, n_edges, rng):
    print(f"[{label}] building checkers", file=sys.stderr)
    ours = CollisionChecker(robot, scene)
    loop = CollisionChecker(robot, scene, broadphase="none")
    naive = NaiveChecker(robot, scene, allocate=False)
    naive_alloc = NaiveChecker(robot, scene, allocate=True)
    states = [robot.random_configuration(rng) for _ in range(n_states)]
    rows = []

    print(f"[{label}] single states x{n_states}", file=sys.stderr)
    t_naive, ref = timed(naive.is_valid, states)
    t_alloc, v_alloc = timed(naive_alloc.is_valid, states)
    t_ours, v_ours = timed(ours.is_valid, states)
    t_loop, v_loop = timed(loop.is_valid, states)
    for verdicts in (v_alloc, v_ours, v_loop):  # GJK-borderline contacts (< 0.1 mm) may differ
        assert np.mean(np.array(verdicts) != np.array(ref)) < 0.002, "verdicts differ from the naive check"
    valid_frac = float(np.mean(ref))
    methods = (("naive", t_naive), ("naive+alloc", t_alloc), ("ours pair loop", t_loop), ("ours is_valid", t_ours))
    for method, t in methods:
        rows.append(dict(robot=label, workload="single state", method=method, us_per_state=1e6 * t / n_states))

    print(f"[{label}] edges x{n_edges}", file=sys.stderr)
    edges = make_edges(robot, naive, rng, n_edges)
    n_edge_states = sum(len(e) for e in edges)
    t_naive, ref_edges = timed(lambda e: all(naive.is_valid(q) for q in e), edges)
    ours.reset_count()
    t_first, first = timed(ours.first_invalid, edges)
    checked_first = ours.check_count / REPEATS
    ours.reset_count()
    t_any, anyinv = timed(ours.any_invalid, edges)
    checked_any = ours.check_count / REPEATS
    agree = np.mean([(f == -1) == r for f, r in zip(first, ref_edges)] + [a != r for a, r in zip(anyinv, ref_edges)])
    assert agree > 0.98, "edge verdicts differ from the naive check"
    edge_valid_frac = float(np.mean(ref_edges))
    for method, t, checked in (
        ("naive", t_naive, n_edge_states),
        ("ours first_invalid", t_first, checked_first),
        ("ours any_invalid", t_any, checked_any),
    ):
        rows.append(
            dict(
                robot=label,
                workload="edge batch",
                method=method,
                us_per_state=1e6 * t / n_edge_states,
                us_per_checked_state=1e6 * t / checked,
                us_per_edge=1e6 * t / len(edges),
            )
        )
    meta = dict(
        robot=label,
        nq=robot.nq,
        geometries=robot.collision_model.ngeoms,
        obstacles=len(scene),
        pairs_ours=ours.n_pairs,
        pairs_naive=naive.n_pairs,
        states=n_states,
        valid_fraction=valid_frac,
        edges=len(edges),
        states_per_edge=n_edge_states / len(edges),
        edge_valid_fraction=edge_valid_frac,
    )
    return rows, meta


def write_outputs(rows, metas, quick):
    RESULTS.mkdir(parents=True, exist_ok=True)
    payload = dict(
        benchmark="collision",
        quick=quick,
        machine=platform.platform(),
        pinocchio=pin.__version__,
        setups=metas,
        rows=rows,
    )
    (RESULTS / "collision.json").write_text(json.dumps(payload, indent=2))
    header = "| robot | workload | method | µs / state | µs / checked state | µs / edge |"
    lines = ["# Collision check cost", "", header]
    lines.append("|---|---|---|---|---|---|")
    for r in rows:
        per_checked = f"{r['us_per_checked_state']:.1f}" if "us_per_checked_state" in r else ""
        per_edge = f"{r['us_per_edge']:.0f}" if "us_per_edge" in r else ""
        lines.append(
            f"| {r['robot']} | {r['workload']} | {r['method']} | {r['us_per_state']:.1f} | {per_checked} | {per_edge} |"
        )
    lines += ["", "| robot | nq | geoms | obstacles | pairs (ours / naive) | valid states | edges | states/edge |"]
    lines.append("|---|---|---|---|---|---|---|---|")
    for m in metas:
        lines.append(
            f"| {m['robot']} | {m['nq']} | {m['geometries']} | {m['obstacles']} | {m['pairs_ours']} / "
            f"{m['pairs_naive']} | {m['valid_fraction']:.0%} | {m['edges']} ({m['edge_valid_fraction']:.0%} valid) "
            f"| {m['states_per_edge']:.1f} |"
        )
    lines += [
        "",
        "µs / state = wall time / all states of the workload (for edges: every discretised state, so early exits",
        "show as a lower cost); µs / checked state = wall time / states actually checked. 2 shared CPU cores:",
        "timings are noisy.",
    ]
    (RESULTS / "collision.md").write_text("\n".join(lines) + "\n")
    plot(rows)


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    robots = list(dict.fromkeys(r["robot"] for r in rows))
    fig, axes = plt.subplots(1, len(robots), figsize=(6 * len(robots), 4))
    for ax, robot in zip(np.atleast_1d(axes), robots):
        sub = [r for r in rows if r["robot"] == robot]
        labels = [f"{r['workload']}\n{r['method']}" for r in sub]
        colors = ["tab:gray" if r["method"].startswith("naive") else "tab:blue" for r in sub]
        ax.barh(labels, [r["us_per_state"] for r in sub], color=colors)
        ax.set_xlabel("µs per state")
        ax.set_title(robot)
        ax.invert_yaxis()
    fig.suptitle("Validity check cost: CollisionChecker (blue) vs naive pinocchio.computeCollisions (grey)")
    fig.tight_layout()
    fig.savefig(RESULTS / "collision.png", dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sample sizes (a few seconds)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    global RESULTS
    RESULTS = results_dir(args.quick)  # --quick: bench/results/quick/, never the committed results
    n_states, n_edges = (300, 30) if args.quick else (3000, 200)
    rng = np.random.default_rng(args.seed)
    setups = [
        ("Maru-1 13-DOF", RobotModel.maru1(), Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml"))),
        ("Panda", load_example_robot("panda"), panda_scene()),
    ]
    rows, metas = [], []
    for label, robot, scene in setups:
        r, m = bench_robot(label, robot, scene, n_states, n_edges, rng)
        rows += r
        metas.append(m)
    write_outputs(rows, metas, args.quick)
    print((RESULTS / "collision.md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
