"""Paper 000 benchmark: RRT, RRT-Connect, goal-biased RRT, PRM and RC-RRT on the 6-DOF and 13-DOF problems.

    .venv/bin/python bench/paper000.py [--quick] [--seeds 30] [--checker coal|spheres]

Every (problem, planner) pair runs ``--seeds`` seeds through ``MotionPlanner.plan`` (the same
code path as the CLI and the ROS node). Reported per pair: success rate, median and p95 solve
time (search only; IK, validation and post-processing are listed apart), nodes, collision
checks and path length (after shortcutting), next to the paper's published row.

PRM: one roadmap of the paper's size (``--prm-nodes``, default 800) per problem, built at the
first query and reused by every later seed: build time and query time are reported apart. Then
the box is moved by 5 cm and the cost of re-validating the roadmap is measured against a rebuild.

Baseline in the same run: OMPL RRTConnect with a plain per-state Python validity checker and
OMPL's own DiscreteMotionValidator at the same resolution (the "naive" way), on both problems.

Writes bench/results/paper000.{json,md,png} and paper000_plan13.png (a planned 13-DOF motion).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import RESULTS, Progress, log, output_dir  # noqa: E402

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig  # noqa: E402
from maru_planner.planning.planners.roadmap import Roadmap  # noqa: E402
from maru_planner.planning.problems import PROBLEMS  # noqa: E402
from maru_planner.planning.space import GroupSpace  # noqa: E402

PLANNERS = ("RRT", "GoalBiasedRRT", "RRTConnect", "PRM", "RCRRT")
# Paper 000, sec. VI (2008 PC): nodes and seconds; PRM: nodes / edges, build and query seconds.
PAPER = {
    ("maru6", "RRT"): {"result": "failed"},
    ("maru6", "PRM"): {"nodes": 656, "edges": 1388, "build": 82.98, "time": 0.08},
    ("maru6", "RRTConnect"): {"nodes": 264, "time": 0.81},
    ("maru6", "GoalBiasedRRT"): {"nodes": 484, "time": 0.469},
    ("maru6", "RCRRT"): {"nodes": 156, "time": 0.395},
    ("maru13", "RRT"): {"result": "failed"},
    ("maru13", "PRM"): {"nodes": 781, "edges": 1560, "build": 91.98, "time": 0.08},
    ("maru13", "RRTConnect"): {"nodes": 782, "time": 6.579},
    ("maru13", "GoalBiasedRRT"): {"nodes": 700, "time": 6.05},
    ("maru13", "RCRRT"): {"nodes": 3750, "time": 76.63},
}


def make_checker(kind: str, robot, scene):
    if kind == "spheres":
        from maru_planner.collision.spheres import SphereCollisionChecker

        return SphereCollisionChecker(robot, scene)
    from maru_planner.collision import CollisionChecker

    return CollisionChecker(robot, scene)


def problem_request(robot, name: str, planner_id: str, budget: float, seed: int) -> MotionRequest:
    prob = PROBLEMS[name]
    names = robot.groups[prob.group]
    start = dict(robot.named_states.get("home", {}))
    start.update(prob.start_dict(names))
    return MotionRequest(
        group=prob.group,
        start=start,
        goal_joints=prob.goal_dict(names),
        planner_id=planner_id,
        time_budget=budget,
        seed=seed,
    )


def summarize(runs: list[dict]) -> dict:
    ok = [r for r in runs if r["success"]]
    times = np.array([r["solve_time"] for r in ok]) if ok else np.array([np.nan])
    out = {
        "runs": len(runs),
        "success": len(ok),
        "success_rate": len(ok) / len(runs) if runs else 0.0,
        "median_time": float(np.median(times)),
        "p95_time": float(np.percentile(times, 95)),
        "median_total_time": float(np.median([r["total_time"] for r in ok])) if ok else float("nan"),
        "median_nodes": float(np.median([r["nodes"] for r in runs])),
        "median_checks": float(np.median([r["collision_checks"] for r in runs])),
        "median_path_length": float(np.median([r["path_length"] for r in ok])) if ok else float("nan"),
        "median_raw_path_length": float(np.median([r["raw_path_length"] for r in ok])) if ok else float("nan"),
        "median_waypoints": float(np.median([r["waypoints"] for r in ok])) if ok else float("nan"),
    }
    builds = [r["roadmap_build_time"] for r in runs if r["roadmap_build_time"] > 0]
    if builds:
        out["roadmap_build_time"] = float(builds[0])
    return out


def run_pair(planner, robot, name, planner_id, budget, seeds, progress) -> list[dict]:
    runs = []
    for seed in range(seeds):
        res = planner.plan(problem_request(robot, name, planner_id, budget, seed))
        row = res.stats.to_dict()
        row.update(success=res.success, status=res.status.value)
        runs.append(row)
        progress.step(f"{name} {planner_id} seed {seed}")
    return runs


def naive_rrtconnect(robot, checker, name: str, budget: float, seeds: int, resolution: float, progress) -> list[dict]:
    """OMPL RRTConnect, per-state Python validity callback, OMPL's DiscreteMotionValidator."""
    from ompl import base as ob
    from ompl import geometric as og

    from maru_planner.planning.motion_planner import seeded_ompl

    prob = PROBLEMS[name]
    idx = np.asarray(robot.group_joint_indices(prob.group))
    base = np.array([robot.named_states.get("home", {}).get(n, 0.0) for n in robot.joint_names])
    gs = GroupSpace(robot.groups[prob.group], idx, robot.lower_limits[idx], robot.upper_limits[idx], base)
    runs = []
    for seed in range(seeds):
        c0 = checker.check_count
        with seeded_ompl(seed):
            ss = og.SimpleSetup(gs.space)
            q = base.copy()

            def valid(state, q=q):
                q[idx] = [state[i] for i in range(len(idx))]
                return bool(checker.is_valid(q))

            ss.setStateValidityChecker(valid)
            si = ss.getSpaceInformation()
            # OMPL's resolution is a fraction of the space extent (L2): match our L-inf step at worst.
            si.setStateValidityCheckingResolution(resolution / si.getMaximumExtent())
            ss.setStartAndGoalStates(gs.to_state(prob.start), gs.to_state(prob.goal))
            planner = og.RRTConnect(si)
            ss.setPlanner(planner)
            t0 = time.perf_counter()
            ss.solve(ob.timedPlannerTerminationCondition(budget))
            dt = time.perf_counter() - t0
            data = ob.PlannerData(si)
            planner.getPlannerData(data)
        ok = ss.haveExactSolutionPath()
        path = np.array([gs.to_array(s) for s in ss.getSolutionPath().getStates()]) if ok else None
        runs.append({
            "success": bool(ok), "solve_time": dt, "total_time": dt, "nodes": data.numVertices(),
            "collision_checks": checker.check_count - c0, "roadmap_build_time": 0.0,
            "path_length": float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()) if ok else float("nan"),
            "raw_path_length": float("nan"), "waypoints": len(path) if ok else 0,
        })  # fmt: skip
        progress.step(f"{name} naive RRTConnect seed {seed}")
    return runs


def revalidation_cost(robot, checker, scene, name: str, resolution: float, nodes: int) -> dict:
    """Build a roadmap, move the box 5 cm, compare re-validating it with rebuilding it."""
    prob = PROBLEMS[name]
    idx = np.asarray(robot.group_joint_indices(prob.group))
    base = np.array([robot.named_states.get("home", {}).get(n, 0.0) for n in robot.joint_names])
    gs = GroupSpace(robot.groups[prob.group], idx, robot.lower_limits[idx], robot.upper_limits[idx], base)
    roadmap = Roadmap(gs, checker, resolution)
    t0 = time.monotonic()
    roadmap.build(nodes, time.monotonic() + 600)
    build = time.monotonic() - t0
    _mode, path = roadmap.query(np.asarray(prob.start), np.asarray(prob.goal), 10.0)
    moved = "box" if "box" in scene else next(iter(scene.obstacles))
    pose = scene.obstacles[moved].pose.copy()
    pose[1, 3] += 0.05
    scene.move(moved, pose)
    t0 = time.monotonic()
    answer_ok = bool(roadmap.edges.path_valid(path)) if path is not None else None
    answer_check = time.monotonic() - t0
    report = roadmap.revalidate()
    pose[1, 3] -= 0.05
    scene.move(moved, pose)
    return {
        "problem": name, "moved": moved, "roadmap_nodes": report.vertices, "roadmap_edges": report.edges,
        "build_time": build, "revalidation_time": report.seconds, "states_checked": report.states_checked,
        "invalid_vertices": report.invalid_vertices, "invalid_edges": report.invalid_edges,
        "answer_check_time": answer_check, "answer_still_free": answer_ok,
    }  # fmt: skip


def fmt(v, digits=3):
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return "—"
    if isinstance(v, float):
        return f"{v:.{digits}g}" if abs(v) < 1000 else f"{v:.0f}"
    return str(v)


def paper_cell(paper: dict) -> str:
    if "result" in paper:
        return paper["result"]
    if "build" in paper:
        return f"{paper['nodes']} / {paper['edges']}, build {paper['build']} s, query {paper['time']} s"
    return f"{paper['nodes']} nodes, {paper['time']} s"


def write_markdown(report: dict, path: Path) -> None:
    lines = [
        "# Paper 000 — five planners on the 6-DOF and 13-DOF problems",
        "",
        f"Checker: `{report['checker']}`, resolution {report['resolution']} rad, seeds {report['seeds']}, "
        f"budgets {report['budgets']}. Times are the search (solve) time in seconds; PRM's is the query on a "
        "reused roadmap, its build time is listed apart. Paper: 2008 PC, OpenGL simulator.",
        "",
        "| problem | planner | success | median s | p95 s | nodes | checks | path rad (raw) | paper |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for row in report["rows"]:
        s = row["summary"]
        extra = f" (build {fmt(s['roadmap_build_time'])} s)" if "roadmap_build_time" in s else ""
        lines.append(
            f"| {row['problem']} | {row['planner']} | {s['success']}/{s['runs']} | {fmt(s['median_time'])}{extra} | "
            f"{fmt(s['p95_time'])} | {fmt(s['median_nodes'])} | {fmt(s['median_checks'])} | "
            f"{fmt(s['median_path_length'])} ({fmt(s['median_raw_path_length'])}) | {row['paper']} |"
        )
    lines += ["", "## PRM roadmap re-validation after moving an obstacle 5 cm", "",
              "MotionPlanner first checks the stale roadmap's answer (\"answer check\"); only a blocked answer "
              "triggers the full re-validation, and a rebuild if anything died.", "",
              "| problem | moved | nodes | edges | build s | answer check s (still free?) | full re-validate s "
              "| states | invalid nodes | invalid edges |",
              "|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in report["revalidation"]:
        lines.append(
            f"| {r['problem']} | {r['moved']} | {r['roadmap_nodes']} | {r['roadmap_edges']} | {fmt(r['build_time'])} | "
            f"{fmt(r['answer_check_time'])} ({r['answer_still_free']}) | {fmt(r['revalidation_time'])} | "
            f"{r['states_checked']} | {r['invalid_vertices']} | {r['invalid_edges']} |"
        )
    lines += ["", "## Targets", ""] + [f"- {t}" for t in report["targets"]]
    path.write_text("\n".join(lines) + "\n")


def targets(report: dict) -> list[str]:
    rows = {(r["problem"], r["planner"]): r["summary"] for r in report["rows"]}
    out = []

    def check(key, label, limit, field="median_time", need_all=True):
        s = rows.get(key)
        if s is None:
            return
        value = s.get(field, float("nan"))
        full = s["success"] == s["runs"]
        hit = bool(np.isfinite(value) and value <= limit and (full or not need_all))
        out.append(
            f"{'MET ' if hit else 'MISSED'} {label}: {fmt(value)} s (limit {limit} s), "
            f"success {s['success']}/{s['runs']}"
        )

    check(("maru13", "RRTConnect"), "13-DOF RRTConnect median <= 0.1 s, 100 %", 0.1)
    check(("maru13", "RCRRT"), "13-DOF RCRRT median <= 5 s, 100 %", 5.0)
    for p in ("GoalBiasedRRT", "RRTConnect", "PRM", "RCRRT"):
        check(("maru6", p), f"6-DOF {p} median <= 0.05 s", 0.05)
    for prob in ("maru6", "maru13"):
        check((prob, "PRM"), f"{prob} PRM roadmap build <= 2 s", 2.0, "roadmap_build_time", need_all=False)
        check((prob, "PRM"), f"{prob} PRM query median <= 0.01 s", 0.01)
    return out


def plot(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for ax, prob in zip(axes, ("maru6", "maru13"), strict=True):
        rows = [r for r in report["rows"] if r["problem"] == prob]
        labels = [r["planner"].replace(" (naive OMPL checker)", "\n(naive)") for r in rows]
        ours = [r["summary"]["median_time"] for r in rows]
        paper = [PAPER.get((prob, r["planner"]), {}).get("time", np.nan) for r in rows]
        x = np.arange(len(rows))
        ax.bar(x - 0.2, [v if np.isfinite(v) else 0 for v in ours], 0.4, label="ours (median solve)")
        ax.bar(x + 0.2, [v if np.isfinite(v) else 0 for v in paper], 0.4, label="paper (2008)")
        for i, r in enumerate(rows):
            s = r["summary"]
            label = f"{s['success']}/{s['runs']}"
            if np.isfinite(ours[i]):
                ax.text(i - 0.2, ours[i], label, ha="center", va="bottom", fontsize=7)
            else:
                ax.text(i - 0.2, 0.02, f"failed\n{label}", ha="center", va="bottom", fontsize=7,
                        transform=ax.get_xaxis_transform())  # fmt: skip
        ax.set_yscale("log")
        ax.set_xticks(x, labels, fontsize=8)
        ax.set_ylabel("seconds (log)")
        ax.set_title(f"{prob}: planning time (success count above our bars)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="5 seeds, short budgets")
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--checker", choices=("coal", "spheres"), default="coal")
    ap.add_argument("--budget", type=float, default=10.0, help="time budget per run (s)")
    ap.add_argument("--rrt-budget", type=float, default=3.0, help="budget of plain RRT (it cannot reach the goal)")
    ap.add_argument("--resolution", type=float, default=PlannerConfig.resolution)
    ap.add_argument("--prm-nodes", type=int, default=800)
    ap.add_argument("--planners", nargs="+", default=list(PLANNERS))
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    args.out = output_dir(args.out, args.quick)  # --quick: bench/results/quick/, never the committed results
    if args.quick:
        args.seeds, args.budget, args.rrt_budget = min(args.seeds, 5), min(args.budget, 5.0), min(args.rrt_budget, 1.0)

    from maru_planner.robot import RobotModel
    from maru_planner.scene import Scene

    robot = RobotModel.maru1()
    problems = ("maru6", "maru13")
    total = len(problems) * (len(args.planners) + 1) * args.seeds
    progress = Progress(total)
    budgets = {p: (args.rrt_budget if p == "RRT" else args.budget) for p in args.planners}
    report = {"checker": args.checker, "resolution": args.resolution, "seeds": args.seeds, "budgets": budgets,
              "prm_nodes": args.prm_nodes, "rows": [], "revalidation": []}  # fmt: skip
    plan13 = None
    for name in problems:
        scene = Scene.from_yaml(PROBLEMS[name].scene_path)
        checker = make_checker(args.checker, robot, scene)
        config = PlannerConfig(resolution=args.resolution, prm_roadmap_nodes=args.prm_nodes)
        for planner_id in args.planners:
            planner = MotionPlanner(robot, checker, config)  # fresh: the PRM roadmap is built at seed 0
            runs = run_pair(planner, robot, name, planner_id, budgets[planner_id], args.seeds, progress)
            report["rows"].append({"problem": name, "planner": planner_id, "summary": summarize(runs), "runs": runs,
                                   "paper": paper_cell(PAPER[(name, planner_id)])})  # fmt: skip
            if name == "maru13" and planner_id == "RRTConnect":
                plan13 = (planner, planner.plan(problem_request(robot, name, planner_id, args.budget, 3)), scene)
        runs = naive_rrtconnect(robot, checker, name, args.budget, args.seeds, args.resolution, progress)
        report["rows"].append({"problem": name, "planner": "RRTConnect (naive OMPL checker)",
                               "summary": summarize(runs), "runs": runs, "paper": "—"})  # fmt: skip
        if "PRM" in args.planners:
            log(f"measuring roadmap re-validation on {name}")
            report["revalidation"].append(
                revalidation_cost(robot, checker, scene, name, args.resolution, args.prm_nodes)
            )
    report["targets"] = targets(report)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "paper000.json").write_text(json.dumps(report, indent=1, default=float))
    write_markdown(report, args.out / "paper000.md")
    plot(report, args.out / "paper000.png")
    if plan13 is not None and plan13[1].success:
        from maru_planner.viz.plans import plot_plan

        planner, res, scene = plan13
        base = np.array([problem_request(robot, "maru13", "RRTConnect", 1, 0).start[n] for n in robot.joint_names])
        plot_plan(robot, scene, res, args.out / "paper000_plan13.png", title="13-DOF upper body, RRTConnect",
                  base_q=base)  # fmt: skip
    print((args.out / "paper000.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
