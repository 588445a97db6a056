"""Fixed-seed plans whose paths must not change when the code is restructured (issue 35).

``python test/golden_paths.py`` writes ``test/data/golden_paths.json`` from the code as it is; the test
(``test_golden_paths.py``) plans the same requests and compares. Regenerate only on purpose, when a change is
meant to change paths, and say so in the commit.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from maru_planner.paths import benchmarks_dir
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig
from maru_planner.planning.problems import PROBLEMS
from maru_planner.robot import load_example_robot
from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN, mbm_panda
from maru_planner.scene import Scene
from maru_planner.scene.motion_bench_maker import iter_mbm_problems

GOLDEN = Path(__file__).resolve().parent / "data" / "golden_paths.json"
MBM_TARBALL = benchmarks_dir() / "motionbenchmaker" / "vamp_panda_problems.tar.bz2"
MARU13_PLANNERS = ("CompiledRRTConnect", "RRTConnect", "RCRRT", "PRM")
MARU13_SEEDS = (1, 2)
MBM_PER_SET = 3
MBM_CASES = 20
MBM_SEED = 7
BUDGET = 30.0  # s: far above what any of these needs, so no deadline decides a path


def _outcome(result) -> dict[str, Any]:
    if not result.success:
        return {"status": result.status.value, "message": result.message}
    traj = result.trajectory
    return {
        "status": result.status.value,
        "path": np.asarray(result.path, dtype=float).tolist(),
        "duration": float(traj.duration),
        "points": len(traj.times),
        "final": np.asarray(traj.positions[-1], dtype=float).tolist(),
    }


def maru13_outcomes() -> dict[str, dict[str, Any]]:
    problem = PROBLEMS["maru13"]
    robot = load_example_robot("maru1")
    names = robot.groups[problem.group]
    planner = MotionPlanner.from_scene(robot, Scene.from_yaml(problem.scene_path), PlannerConfig())
    out = {}
    for planner_id in MARU13_PLANNERS:
        for seed in MARU13_SEEDS:
            request = MotionRequest(
                problem.group,
                start=problem.start_dict(names),
                goal_joints=problem.goal_dict(names),
                planner_id=planner_id,
                time_budget=BUDGET,
                seed=seed,
            )
            out[f"maru13/{planner_id}/{seed}"] = _outcome(planner.plan(request))
    return out


def mbm_outcomes() -> dict[str, dict[str, Any]]:
    robot = mbm_panda()
    planner = MotionPlanner.from_scene(robot, None, PlannerConfig())
    arm = set(robot.groups["arm"])
    out = {}
    problems = iter_mbm_problems(MBM_TARBALL, limit_per_set=MBM_PER_SET, fixed_joints=PANDA_FINGERS_OPEN)
    for problem in list(problems)[:MBM_CASES]:
        planner.set_scene(problem.scene)
        goal = {k: v for k, v in problem.request.goal.items() if k in arm}
        request = MotionRequest("arm", start=problem.request.start, goal_joints=goal, time_budget=BUDGET, seed=MBM_SEED)
        out[problem.name] = _outcome(planner.plan(request))
    return out


def outcomes() -> dict[str, dict[str, Any]]:
    return {**maru13_outcomes(), **mbm_outcomes()}


if __name__ == "__main__":
    outcomes()  # once to compile every kernel in numba's cache: a cold compile could spend a budget
    GOLDEN.write_text(json.dumps(outcomes(), indent=1) + "\n")
    print(f"wrote {GOLDEN}", file=sys.stderr)
