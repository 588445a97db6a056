"""RC-RRT's compiled loop (rcrrt_kernel) on a sphere checker: a lattice path whose every edge the checker passes,
each lattice point at most once in the tree, exhaustion of a finite lattice, same seed same path, growing arrays,
and the facade's certified paths."""

from __future__ import annotations

import numpy as np
import pytest
from ompl import base as ob
from ompl import geometric as og

from maru_planner.collision.spheres import SphereCollisionChecker
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.planners import rc_rrt
from maru_planner.planning.planners.rc_rrt import RCRRT
from maru_planner.planning.problems import PROBLEMS
from maru_planner.planning.space import EdgeChecker, GroupSpace
from maru_planner.scene import Obstacle, Scene

ARM = [f"panda_joint{i}" for i in range(1, 8)]
RESOLUTION = 0.05
STEP = 0.3
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]  # the arm bent, its hand in front of the robot


def arm_space(robot, half_width: float | None = None) -> GroupSpace:
    """The Panda arm's space from :data:`READY`; ``half_width``: only that far (rad) around it."""
    indices = robot.joint_indices(ARM)
    base = robot.neutral()
    base[indices] = READY
    lower, upper = robot.lower_limits[indices], robot.upper_limits[indices]
    if half_width is not None:
        lower, upper = base[indices] - half_width, base[indices] + half_width
    return GroupSpace(ARM, indices, lower, upper, base)


def wall_scene() -> Scene:
    """A wall in the way of the hand when joint 1 turns it to the left (~60-100 collisions a search)."""
    return Scene([Obstacle("wall", "box", size=[0.4, 0.05, 0.8], pose=[0.3, 0.3, 0.4])])


def plan(robot, gs: GroupSpace, goal, seed: int = 3, scene: Scene | None = None, seconds: float = 20.0,
         checker_options: dict | None = None, **params):  # fmt: skip
    checker = SphereCollisionChecker(robot, scene, **(checker_options or {}))
    edges = EdgeChecker(gs, checker, RESOLUTION)
    ss = og.SimpleSetup(gs.space)
    planner = RCRRT(ss.getSpaceInformation(), edges)
    planner.params().set_params({"step": STEP, "seed": seed, **params})
    ss.setPlanner(planner)
    ss.setStateValidityChecker(lambda _state: True)
    ss.setStartAndGoalStates(gs.to_state(gs.base[gs.indices]), gs.to_state(np.asarray(goal, float)))
    status = ss.solve(ob.timedPlannerTerminationCondition(seconds))
    path = np.array([gs.to_array(s) for s in ss.getSolutionPath().getStates()]) if ss.haveExactSolutionPath() else None
    return planner, edges, status, path


def far_goal(gs: GroupSpace) -> np.ndarray:
    start = gs.base[gs.indices]
    return np.clip(start + np.array([2.2, 0.3, 0.0, 0.3, 0.0, 0.0, 0.0]), gs.lower, gs.upper)


@pytest.fixture(scope="module", autouse=True)
def compiled_loop(panda):
    """numba compiles the loop on its first call after a change: outside the tests' termination conditions."""
    gs = arm_space(panda)
    plan(panda, gs, np.clip(gs.base[gs.indices] + 0.01, gs.lower, gs.upper), seconds=120.0)


def lattice_steps(path: np.ndarray, start: np.ndarray) -> np.ndarray:
    return (path - start) / STEP


def test_runs_compiled_on_a_numba_sphere_checker_and_finds_a_lattice_path_the_checker_passes(panda):
    gs = arm_space(panda)
    goal = far_goal(gs)
    planner, edges, status, path = plan(panda, gs, goal, scene=wall_scene())
    assert planner.compiled and status == ob.PlannerStatus.EXACT_SOLUTION
    start = gs.base[gs.indices]
    np.testing.assert_allclose(path[0], start)
    np.testing.assert_allclose(path[-1], goal)
    steps = lattice_steps(path[:-1], start)
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)  # every node but the goal is on the lattice
    moves = np.abs(np.diff(np.round(steps), axis=0))
    assert np.all(moves.sum(axis=1) == 1)  # one input: one joint by one step
    assert np.abs(goal - path[-2]).max() <= rc_rrt.RCRRT_PARAMS["goal_range"].default + 1e-12
    assert all(edges.edge_valid(a, b) for a, b in zip(path[:-1], path[1:], strict=True))


@pytest.mark.parametrize("options", [{"grid_min_obstacles": 1}, {"confirm": False}], ids=["grid", "pure-spheres"])
def test_through_the_grid_scan_and_on_the_pure_sphere_model_every_edge_is_one_the_checker_passes(panda, options):
    """A large scene's grid broad phase (the checker's own scan per edge), and a checker that leaves no state to the
    exact model (ambiguous ones collide)."""
    gs = arm_space(panda)
    planner, edges, status, path = plan(panda, gs, far_goal(gs), scene=wall_scene(), checker_options=options)
    assert edges.checker.uses_grid == ("grid_min_obstacles" in options)
    assert planner.compiled and status == ob.PlannerStatus.EXACT_SOLUTION and planner.collisions > 0
    assert all(edges.edge_valid(a, b) for a, b in zip(path[:-1], path[1:], strict=True))


def test_each_lattice_point_is_in_the_tree_once_and_children_are_one_input_from_their_parent(panda):
    gs = arm_space(panda)
    planner, _, status, _ = plan(panda, gs, far_goal(gs), scene=wall_scene(), seed=5)
    assert status == ob.PlannerStatus.EXACT_SOLUTION
    n = planner.count
    lattice = np.delete(np.arange(n), planner.goal_node)
    steps = np.round(lattice_steps(planner.X[lattice], gs.base[gs.indices])).astype(int)
    assert len({tuple(row) for row in steps}) == len(lattice)
    children = lattice[1:]
    moves = np.abs(np.round(lattice_steps(planner.X[children] - planner.X[planner.parent[children]], 0.0)))
    assert np.all(moves.sum(axis=1) == 1)


def reachable_lattice_points(edges: EdgeChecker, start: np.ndarray, half_width: float) -> int:
    """Lattice points ``start + STEP·n`` within ``half_width`` reached from the start by free one-step edges (BFS)."""
    reach = int(round(half_width // STEP))
    seen, frontier = {(0,) * len(start)}, [(0,) * len(start)]
    while frontier:
        n = frontier.pop()
        for axis in range(len(start)):
            for sign in (1, -1):
                m = n[:axis] + (n[axis] + sign,) + n[axis + 1 :]
                if abs(m[axis]) <= reach and m not in seen:
                    if edges.edge_valid(start + STEP * np.array(n), start + STEP * np.array(m)):
                        seen.add(m)
                        frontier.append(m)
    return len(seen)


def test_a_goal_off_the_lattice_out_of_range_exhausts_the_lattice_reachable_from_the_start(panda):
    """Limits ±0.45 rad with a 0.3 rad step: 3 lattice values per joint, 3^7 points; goal_range 0 never tries the
    goal edge, so every input of every node is spent: INFEASIBLE with a proof, every reachable point visited."""
    gs = arm_space(panda, half_width=0.45)
    planner, edges, status, _ = plan(panda, gs, gs.base[gs.indices] + 0.1, scene=wall_scene(), goal_range=0.0,
                                     seconds=60.0)  # fmt: skip
    assert status == ob.PlannerStatus.INFEASIBLE and planner.exhausted
    assert planner.count == reachable_lattice_points(edges, gs.base[gs.indices], 0.45) > 1024  # arrays grew
    assert "no path exists at step 0.3 rad" in planner.failure_proof()
    assert not planner.active[: planner.count].any() and not planner.untried[: planner.count].any()


def test_same_seed_same_path_other_seed_other_path(panda):
    gs = arm_space(panda)
    goal = far_goal(gs)
    paths = [plan(panda, gs, goal, seed=seed, scene=wall_scene())[3] for seed in (7, 7, 8)]
    np.testing.assert_array_equal(paths[0], paths[1])
    assert paths[0].shape != paths[2].shape or not np.array_equal(paths[0], paths[2])


def test_collisions_raise_sigma_of_the_node_and_its_ancestors(panda):
    gs = arm_space(panda)
    planner, _, _, _ = plan(panda, gs, far_goal(gs), scene=wall_scene(), seed=2)
    assert planner.collisions > 0
    sigma = planner.sigma[: planner.count]
    assert sigma.max() > 0 and sigma.max() <= 1.0
    raised = np.flatnonzero(sigma > 0)
    parents = planner.parent[raised]
    assert np.all(sigma[parents[parents >= 0]] > 0)  # a raise reaches the parent too


def test_planner_data_holds_the_whole_tree(panda):
    gs = arm_space(panda)
    planner, _, _, _ = plan(panda, gs, far_goal(gs), scene=wall_scene())
    data = ob.PlannerData(planner.getSpaceInformation())
    planner.getPlannerData(data)
    assert data.numVertices() == planner.count and data.numEdges() == planner.count - 1
    assert planner.graph_size() == (planner.count, planner.count - 1)


def test_arrays_grow_from_a_small_capacity_to_the_same_path(panda, monkeypatch):
    gs = arm_space(panda)
    goal = far_goal(gs)
    reference = plan(panda, gs, goal, seed=4, scene=wall_scene())[3]
    monkeypatch.setattr(rc_rrt, "COMPILED_CAPACITY", 3)  # not a power of two either
    np.testing.assert_array_equal(plan(panda, gs, goal, seed=4, scene=wall_scene())[3], reference)


def test_the_facade_plans_maru1_with_it_on_spheres_and_certifies_the_path(maru1):
    problem = PROBLEMS["maru13"]
    planner = MotionPlanner.from_scene(maru1, Scene.from_yaml(problem.scene_path), PlannerConfig())
    names = maru1.groups[problem.group]
    result = planner.plan(MotionRequest(problem.group, start=problem.start_dict(names),
                                        goal_joints=problem.goal_dict(names), planner_id="RCRRT", time_budget=20.0,
                                        seed=1))  # fmt: skip
    assert result.status is PlanStatus.SUCCESS, result.message
    assert result.stats.certified and result.stats.collision_model == "spheres"


def test_a_goal_it_cannot_reach_ends_at_the_termination_condition_with_the_tree_kept(panda):
    """goal_range 0 and a goal off the lattice in the whole arm space: no proof and no path, only the timeout."""
    gs = arm_space(panda)
    goal = np.clip(gs.base[gs.indices] + 0.1, gs.lower, gs.upper)
    planner, _, status, path = plan(panda, gs, goal, scene=wall_scene(), goal_range=0.0, seconds=0.3)
    assert status == ob.PlannerStatus.TIMEOUT and path is None
    assert not planner.exhausted and planner.failure_proof() is None
    assert planner.count > 1 and planner.goal_node == -1
