"""The arm planner registry: specs, parameters through the planners' ParamSet, and a toy planner that
the facade, ``maru-plan`` and the parametrised planner tests pick up with no other edit."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from ompl import geometric as og
from planning_toy_planner import TOY_SPEC
from planning_toys import BoxWorldChecker, ToyRobot, maze_checker

from maru_planner.errors import InvalidPlanner, InvalidRequest
from maru_planner.planning import PLANNERS, MotionPlanner, MotionRequest, PlannerConfig, PlanStatus, planner_ids
from maru_planner.planning.cli import build_parser, main
from maru_planner.planning.planners.registry import (
    CAPABILITIES,
    ArmPlannerSpec,
    get_spec,
    make_planner,
    merged_params,
    register,
)
from maru_planner.planning.space import GroupSpace

TEST_DIR = Path(__file__).resolve().parents[3]
BUILT_IN = ["RRT", "RRTConnect", "PRM", "GoalBiasedRRT", "RCRRT"]


@pytest.fixture
def toy():
    register(TOY_SPEC)
    yield TOY_SPEC
    PLANNERS.pop(TOY_SPEC.id)


def toy_request(planner_id: str, **kw) -> MotionRequest:
    kw.setdefault("time_budget", 3.0)
    kw.setdefault("seed", 1)
    return MotionRequest("all", start={"j0": 0.05, "j1": 0.05}, goal_joints={"j0": 0.95, "j1": 0.95},
                         planner_id=planner_id, **kw)  # fmt: skip


# --- specs ------------------------------------------------------------------------------------
def test_built_in_planners_keep_their_ids_defaults_and_capabilities():
    assert planner_ids()[:5] == BUILT_IN
    assert merged_params("RRT", None) == {"range": 0.0, "goal_bias": 0.0}
    assert merged_params("GoalBiasedRRT", None) == {"range": 0.0, "goal_bias": 0.05}
    assert merged_params("RRTConnect", None) == {"range": 0.0}
    assert merged_params("PRM", None) == {"max_nearest_neighbors": 3}
    assert merged_params("RCRRT", None) == {"step": 0.3, "goal_bias": 0.1, "candidates": 8, "goal_range": 1.5,
                                            "seed": None}  # fmt: skip
    assert get_spec("PRM").has("roadmap") and get_spec("RCRRT").has("resolution_complete")
    for spec in PLANNERS.values():
        assert spec.capabilities <= CAPABILITIES.keys() and spec.description
        assert all(name == p.name and p.description for name, p in spec.params.items())


def test_unknown_ids_parameters_and_values_are_typed_errors():
    with pytest.raises(InvalidPlanner, match="unknown planner 'AStar'; known: RRT, RRTConnect"):
        get_spec("AStar")
    with pytest.raises(InvalidRequest, match="planner PRM has no parameter 'range'; known: max_nearest_neighbors"):
        merged_params("PRM", {"range": 1.0})
    with pytest.raises(InvalidRequest, match="planner RRT: parameter 'goal_bias' = 2.0 is outside"):
        merged_params("RRT", {"goal_bias": 2.0})
    with pytest.raises(ValueError, match="unknown capabilities flying"):
        register(ArmPlannerSpec("Bad", "x", TOY_SPEC.factory, {}, frozenset({"flying"})))
    assert "Bad" not in PLANNERS


def test_parameters_reach_the_ompl_planners_through_their_declared_setters():
    gs = GroupSpace(["x", "y"], [0, 1], [0, 0], [1, 1], [0, 0])
    si = og.SimpleSetup(gs.space).getSpaceInformation()
    rrt = make_planner("GoalBiasedRRT", si, {"range": 0.25})
    assert rrt.getName() == "GoalBiasedRRT" and rrt.getRange() == 0.25 and rrt.getGoalBias() == 0.05
    assert make_planner("PRM", si, {"max_nearest_neighbors": 7}).getMaxNearestNeighbors() == 7
    rcrrt = make_planner("RCRRT", si, {"step": 0.1})
    assert rcrrt.params().get_param("step") == 0.1 and rcrrt.params().get_param("candidates") == 8


def test_a_bad_planner_parameter_in_the_config_is_a_request_error():
    mp = MotionPlanner(ToyRobot(2), maze_checker(), PlannerConfig(planner_params={"RCRRT": {"step": -1.0}}))
    res = mp.plan(toy_request("RCRRT"))
    assert res.status is PlanStatus.INVALID_REQUEST and "parameter 'step'" in res.message


# --- a toy planner: one spec, picked up everywhere --------------------------------------------
def test_a_registered_toy_is_planned_through_the_facade(toy):
    assert "Toy" in planner_ids()
    free = MotionPlanner(ToyRobot(2), BoxWorldChecker([]), PlannerConfig(resolution=0.01)).plan(toy_request("Toy"))
    assert free.success and free.stats.planner_id == "Toy" and free.stats.nodes == 1  # the straight line
    config = PlannerConfig(resolution=0.01, planner_params={"Toy": {"step": 0.1}})
    maze = MotionPlanner(ToyRobot(2), maze_checker(), config)
    res = maze.plan(toy_request("Toy", simplify=False))
    assert res.success, res.message
    assert res.stats.nodes > 1 and res.stats.edges == res.stats.nodes - 1  # its graph_size hook
    bad = maze.plan(toy_request("Toy2"))
    assert bad.status is PlanStatus.INVALID_PLANNER and "Toy" in bad.message


def test_a_registered_toy_is_offered_and_accepted_by_maru_plan(toy, tmp_path):
    help_text = build_parser().format_help()
    assert "Toy: straight line if free, else a tiny RRT" in help_text
    assert "step (default 0.05): RRT extension length (rad); range [0.001, 1]" in help_text
    out = tmp_path / "toy.json"
    code = main(["--problem", "maru6", "--scene", "none", "--planner", "Toy", "--param", "step=0.2", "--seed", "2",
                 "--json", str(out), "--quiet"])  # fmt: skip
    data = json.loads(out.read_text())
    assert code == 0 and data["success"] and data["stats"]["planner_id"] == "Toy", data["message"]
    assert main(["--problem", "maru6", "--planner", "Toy", "--param", "step=9", "--json", str(out), "--quiet"]) == 2
    assert "parameter 'step' = 9.0 is outside [0.001, 1]" in json.loads(out.read_text())["message"]


def test_the_parametrised_planner_tests_run_a_registered_toy():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(TEST_DIR), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "planning_toy_planner", "-q", "-rA",
         str(TEST_DIR / "unit" / "planning" / "test_planning_core.py"), "-k", "Toy and (every_planner or same_seed)"],
        capture_output=True, text=True, env=env, cwd=TEST_DIR.parent, timeout=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    for test in ("test_every_planner_solves_the_maze[Toy]", "test_same_seed_same_path[Toy]"):
        assert f"PASSED test/unit/planning/test_planning_core.py::{test}" in proc.stdout, proc.stdout[-3000:]


def test_toy_paths_are_straight_when_free(toy):
    res = MotionPlanner(ToyRobot(2), BoxWorldChecker([]), PlannerConfig()).plan(toy_request("Toy", simplify=False))
    assert np.allclose(res.path, [[0.05, 0.05], [0.95, 0.95]])
