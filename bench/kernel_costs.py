"""Cost of one checked state in the search kernel, against the naive per-state exact check (issue 16's floor).

    .venv/bin/python bench/kernel_costs.py [--mbm-per-set 3] [--seeds 5] [--repeats 20] [--quick]

What ``CompiledRRTConnect`` pays per state it checks, on the states of real problems:
- path: the certified paths ours plans (``bench/peers_arm.py``'s configuration of ours), every 0.05 rad (L-inf):
  free states, many near obstacles;
- random: uniform in the group's joint limits (the others at the start): what the sampler proposes, many colliding.

Per state, the median over the problems of: forward kinematics alone (``kernels.fk.joint_poses_nb``), the sphere
model's whole answer (``kernels.state_validity.classify``: kinematics, robot spheres against the scene and the self
pairs, as the search kernel runs it; pure sphere model, first touch ends it), and the baseline:
``pinocchio.computeCollisions`` on the exact meshes, the naive OMPL peer's check. Problems: the first
``--mbm-per-set`` MotionBenchMaker Panda problems of each set and ``--seeds`` seeds of the Maru-1 13-DOF problem.
VAMP's published figure (whole problems, 35 µs median, C++ SIMD) is quoted, not measured.

Outputs bench/results/kernel_costs.{json,md,png}; progress on stderr.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from _common import RESULTS, Progress, require_data, write_results  # noqa: E402
from numba import njit  # noqa: E402
from peers_arm import TARBALL, VAMP_PUBLISHED, Case, Ours, full_q, maru13_case, mbm_cases, peer_geometry  # noqa: E402

from maru_planner.collision.kernels.fk import joint_poses_nb  # noqa: E402
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene  # noqa: E402
from maru_planner.collision.kernels.state_validity import classify, work_arrays  # noqa: E402
from maru_planner.planning.space import edge_states, full_configurations  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.robots.panda import mbm_panda  # noqa: E402

STEP = 0.05  # rad, L-inf: the motion resolution of ours in bench/peers_arm.py
RANDOM_STATES = 400


@njit(cache=True)
def _forward_kinematics(states, ri, rf, sf, repeats):
    """Forward kinematics of every state, ``repeats`` times."""
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    work = work_arrays(robot, scene)
    parent, kind, axis, prot, ppos, idx_q = robot[:6]
    for _ in range(repeats):
        for i in range(states.shape[0]):
            joint_poses_nb(states[i], parent, kind, axis, prot, ppos, idx_q, work[0], work[1])


@njit(cache=True)
def _classify_all(states, ri, rf, sf, repeats):
    """The sphere model's answer for every state, ``repeats`` times; how many collide (or touch)."""
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    work = work_arrays(robot, scene)
    colliding = 0
    for _ in range(repeats):
        colliding = 0
        for i in range(states.shape[0]):
            colliding += classify(states[i], robot, scene, work, True) != 0
    return colliding


def _sphere_costs(states: np.ndarray, kernel_inputs: tuple, repeats: int) -> tuple[float, float, int]:
    """Seconds per state of forward kinematics alone and of the sphere model's whole answer; how many collide."""
    ri, rf, sf = kernel_inputs
    _forward_kinematics(states[:1], ri, rf, sf, 1)  # compiled or loaded before the clock starts
    _classify_all(states[:1], ri, rf, sf, 1)
    t0 = time.perf_counter()
    _forward_kinematics(states, ri, rf, sf, repeats)
    t1 = time.perf_counter()
    colliding = _classify_all(states, ri, rf, sf, repeats)
    t2 = time.perf_counter()
    n = repeats * len(states)
    return (t1 - t0) / n, (t2 - t1) / n, int(colliding)


class _ExactCheck:
    """``pinocchio.computeCollisions`` on ``case``'s exact model (the naive OMPL peer's check), built once."""

    def __init__(self, case: Case):
        self.model, self.geom = peer_geometry(case.robot, case.scene, None)
        self.data, self.gdata = self.model.createData(), pin.GeometryData(self.geom)

    def seconds_per_state(self, states: np.ndarray, repeats: int) -> float:
        t0 = time.perf_counter()
        for _ in range(repeats):
            for q in states:
                pin.computeCollisions(self.model, self.data, self.geom, self.gdata, q, True)
        return (time.perf_counter() - t0) / (repeats * len(states))


def _states(case: Case, ours: Ours, seed: int, rng: np.random.Generator) -> dict[str, np.ndarray] | None:
    """Full configurations along ours' path of ``case`` every STEP (the states an edge check makes), and
    RANDOM_STATES uniform in the group's limits."""
    result = ours.planner.plan(ours.request(case, 1.0, seed))
    if not result.success:
        return None
    robot = case.robot
    indices = robot.joint_indices(result.joint_names)
    path = np.asarray(result.path, dtype=float)
    along = np.concatenate([path[:1]] + [edge_states(a, b, STEP) for a, b in zip(path[:-1], path[1:])])
    random = rng.uniform(robot.lower_limits[indices], robot.upper_limits[indices], (RANDOM_STATES, len(indices)))
    base = full_q(robot, case.start)
    return {"path": full_configurations(base, indices, along), "random": full_configurations(base, indices, random)}


def measure(family: str, cases: list[tuple[Case, int]], ours: Ours, repeats: int, progress: Progress) -> dict:
    rng = np.random.default_rng(0)
    per_kind: dict[str, dict[str, list[float]]] = {}
    for case, seed in cases:
        ours.planner.set_scene(case.scene)
        states = _states(case, ours, seed, rng)
        progress.step(f"{family} {case.name}")
        if states is None:
            continue
        inputs = ours.planner.checker.kernel_inputs()
        if inputs[3][0] > 0:  # the kernel would scan its grid, not classify: not this measurement
            continue
        exact = _ExactCheck(case)
        for kind, q in states.items():
            fk, sphere, colliding = _sphere_costs(q, inputs[:3], repeats)
            row = per_kind.setdefault(kind, {"fk": [], "sphere": [], "exact": [], "colliding": [], "states": []})
            row["fk"].append(fk)
            row["sphere"].append(sphere)
            row["exact"].append(exact.seconds_per_state(q, max(1, repeats // 10)))
            row["colliding"].append(colliding / len(q))
            row["states"].append(len(q))
    return {kind: {"problems": len(row["fk"]), "states": int(np.sum(row["states"])),
                   **{f"median_{k}": float(np.median(row[k])) for k in ("fk", "sphere", "exact", "colliding")}}
            for kind, row in per_kind.items()}  # fmt: skip


def markdown(results: dict) -> str:
    lines = ["# Cost of one checked state (median over problems, µs)", "",
             "| problems | states | n problems | n states | colliding | forward kinematics | sphere model (whole "
             "answer) | exact meshes (naive peer) | exact / sphere |",
             "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for family, kinds in results["runs"].items():
        for kind, row in kinds.items():
            cells = [
                family,
                kind,
                str(row["problems"]),
                str(row["states"]),
                f"{100 * row['median_colliding']:.0f} %",
                f"{1e6 * row['median_fk']:.2f}",
                f"{1e6 * row['median_sphere']:.2f}",
                f"{1e6 * row['median_exact']:.1f}",
                f"{row['median_exact'] / row['median_sphere']:.0f}x",
            ]
            lines.append("| " + " | ".join(cells) + " |")
    lines += ["", f"VAMP (published, C++ SIMD): {1e6 * VAMP_PUBLISHED['mbm_panda_median_s']:.0f} µs per whole "
              "MotionBenchMaker problem (median), not per state."]  # fmt: skip
    return "\n".join(lines) + "\n"


def plot(results: dict, path: Path) -> None:
    labels, series = [], {"forward kinematics": [], "sphere model": [], "exact meshes (naive peer)": []}
    for family, kinds in results["runs"].items():
        for kind, row in kinds.items():
            labels.append(f"{family}\n{kind}")
            for name, key in zip(series, ("median_fk", "median_sphere", "median_exact"), strict=True):
                series[name].append(1e6 * row[key])
    fig, ax = plt.subplots(figsize=(8, 4.5))
    x, width = np.arange(len(labels)), 0.27
    for i, (name, values) in enumerate(series.items()):
        ax.bar(x + (i - 1) * width, values, width, label=name)
    ax.set_xticks(x, labels)
    ax.set_yscale("log")
    ax.set_ylabel("µs per checked state (median over problems)")
    ax.set_title("One state check: our sphere kernel vs the naive exact check")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mbm-per-set", type=int, default=3, help="MotionBenchMaker problems per set (0: none)")
    ap.add_argument("--seeds", type=int, default=5, help="seeds of the Maru-1 problem")
    ap.add_argument("--repeats", type=int, default=20, help="timed passes over each problem's states")
    ap.add_argument("--quick", action="store_true", help="1 problem per MotionBenchMaker set, 1 seed, 3 repeats")
    ap.add_argument("--out", type=Path, default=RESULTS / "kernel_costs")
    args = ap.parse_args(argv)
    if args.quick:
        args.mbm_per_set, args.seeds, args.repeats = min(args.mbm_per_set, 1), 1, 3
    if args.repeats < 1 or min(args.seeds, args.mbm_per_set) < 0:
        ap.error("--repeats must be >= 1, --seeds and --mbm-per-set >= 0")
    if args.mbm_per_set > 0:
        require_data(TARBALL)  # or --mbm-per-set 0: the Maru-1 rows only
    families: dict[str, tuple[Ours, list[tuple[Case, int]]]] = {}
    maru = RobotModel.maru1()
    maru_cases = [(maru13_case(maru), seed) for seed in range(args.seeds)]
    families["maru13"] = (Ours(maru, 0.05, 0.01, "CompiledRRTConnect"), maru_cases)
    if args.mbm_per_set > 0:
        panda = mbm_panda()
        families["mbm"] = (Ours(panda, 0.05, 0.01, "CompiledRRTConnect"),
                           [(case, 0) for case in mbm_cases(panda, args.mbm_per_set)])  # fmt: skip
    progress = Progress(sum(len(cases) for _, cases in families.values()))
    results: dict = {"config": vars(args) | {"out": str(args.out), "step": STEP, "random_states": RANDOM_STATES},
                     "vamp_published_problem_s": VAMP_PUBLISHED["mbm_panda_median_s"], "runs": {}}  # fmt: skip
    for family, (ours, cases) in families.items():
        results["runs"][family] = measure(family, cases, ours, args.repeats, progress)
    write_results(args.out, results, markdown(results), lambda path: plot(results, path), quick=args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
