"""RC-RRT (Cheng & LaValle) behaviour on small 2-D worlds."""

from __future__ import annotations

import numpy as np
import pytest
from ompl import base as ob
from ompl import geometric as og
from planning_toys import BoxWorldChecker, closed_maze_checker, maze_checker

from maru_planner.errors import InvalidRequest
from maru_planner.planning.motion_planner import seeded_ompl
from maru_planner.planning.planners.rc_rrt import RCRRT
from maru_planner.planning.space import BatchedMotionValidator, EdgeChecker, GroupSpace, make_validity_fn

START = [0.05, 0.05]
GOAL = [0.95, 0.95]


class RecordingEdges(EdgeChecker):
    """Edge checker that remembers every edge it was asked about."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.asked: list[tuple] = []

    def edge_valid(self, qa, qb):
        self.asked.append((tuple(np.round(qa, 9)), tuple(np.round(qb, 9))))
        return super().edge_valid(qa, qb)


def make_rcrrt(checker, step=0.05, seed=1, goal=GOAL, start=START, resolution=0.01):
    gs = GroupSpace(["x", "y"], [0, 1], [0, 0], [1, 1], [0.5, 0.5])
    edges = RecordingEdges(gs, checker, resolution)
    with seeded_ompl(seed):
        ss = og.SimpleSetup(gs.space)
        si = ss.getSpaceInformation()
        ss.setStateValidityChecker(make_validity_fn(edges))
        si.setMotionValidator(BatchedMotionValidator(si, edges))
        ss.setStartAndGoalStates(gs.to_state(start), gs.to_state(goal))
        planner = RCRRT(si, edges)
        planner.params().set_params({"step": step, "seed": seed})
        ss.setPlanner(planner)
    return ss, planner, gs, edges


def prepare(planner, origin=(0.5, 0.5)):
    """An empty 2-D tree on the unit square with a 0.05 lattice through ``origin``."""
    planner._reset_tree(2)
    planner._step = 0.05
    planner.lower, planner.upper = np.zeros(2), np.ones(2)
    planner._prepare_lattice(np.array(origin))


def solve(ss, seconds=10.0):
    return ss.solve(ob.timedPlannerTerminationCondition(seconds))


def solution(ss, gs):
    return np.array([gs.to_array(s) for s in ss.getSolutionPath().getStates()])


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_resolution_complete_on_maze(seed):
    ss, planner, gs, edges = make_rcrrt(maze_checker(), seed=seed)
    solve(ss)
    assert ss.haveExactSolutionPath()
    path = solution(ss, gs)
    assert np.allclose(path[0], START) and np.allclose(path[-1], GOAL)
    assert edges.path_valid(path)
    # Every edge but the last (to the goal) is one lattice step along one axis.
    steps = np.abs(np.diff(path[:-1], axis=0))
    assert np.allclose(np.sort(steps, axis=1)[:, -1], 0.05) and np.allclose(np.sort(steps, axis=1)[:, 0], 0.0)


def test_exhausts_lattice_when_no_path_exists():
    ss, planner, gs, edges = make_rcrrt(closed_maze_checker(), seed=4)
    solve(ss, seconds=20.0)
    assert not ss.haveExactSolutionPath()
    assert planner.exhausted
    assert f"all {planner.count} lattice nodes: no path exists at step 0.05 rad" in planner.failure_proof()
    assert not planner.active[: planner.count].any()
    assert (planner.untried[: planner.count] == 0).all()


def test_an_input_is_never_tried_twice_from_a_node():
    ss, planner, gs, edges = make_rcrrt(closed_maze_checker(), seed=5)
    solve(ss, seconds=20.0)
    lattice_edges = [e for e in edges.asked if np.max(np.abs(np.subtract(e[1], e[0]))) <= 0.05 + 1e-9]
    assert len(lattice_edges) > 100
    assert len(set(lattice_edges)) == len(lattice_edges)


def test_exhausted_nodes_are_never_chosen():
    ss, planner, gs, edges = make_rcrrt(maze_checker(), seed=6)
    chosen_untried = []
    original = planner._extend

    def spy(i, target):
        chosen_untried.append(int(planner.untried[i]))
        return original(i, target)

    planner._extend = spy
    solve(ss)
    assert ss.haveExactSolutionPath()
    assert chosen_untried and min(chosen_untried) > 0


def test_sigma_rises_on_collisions_and_propagates_to_ancestors():
    ss, planner, gs, edges = make_rcrrt(maze_checker(), seed=7)
    solve(ss)
    assert planner.collisions > 0
    assert (planner.sigma[: planner.count] > 0).any()
    assert planner.sigma.max() <= 1.0
    # Direct check of the update rule on a three-node chain: +1/m, +1/m^2, +1/m^3.
    prepare(planner)
    a = planner._add_node(np.array([0.5, 0.5]), planner.encode((0, 0)), -1)
    b = planner._add_node(np.array([0.55, 0.5]), planner.encode((1, 0)), a)
    c = planner._add_node(np.array([0.6, 0.5]), planner.encode((2, 0)), b)
    planner._raise_sigma(c)
    assert planner.sigma[c] == pytest.approx(1 / 4)
    assert planner.sigma[b] == pytest.approx(1 / 16)
    assert planner.sigma[a] == pytest.approx(1 / 64)


def test_modified_nearest_neighbour_accepts_with_probability_one_minus_sigma():
    ss, planner, gs, edges = make_rcrrt(BoxWorldChecker([]), seed=8)
    prepare(planner)
    near = planner._add_node(np.array([0.5, 0.5]), planner.encode((0, 0)), -1)
    far = planner._add_node(np.array([0.7, 0.5]), planner.encode((4, 0)), near)
    rng = np.random.default_rng(0)
    target = np.array([0.45, 0.5])
    planner.sigma[near] = 1.0  # always rejected while another candidate accepts
    assert all(planner._select(target, 8, rng) == far for _ in range(50))
    planner.sigma[far] = 1.0  # nobody accepts: fall back to the nearest with untried inputs
    assert planner._select(target, 8, rng) == near
    planner.sigma[:] = 0.5
    picks = [planner._select(target, 8, rng) for _ in range(2000)]
    # near: accepted (1/2) or both rejected and the fallback takes the nearest (1/4)
    assert 0.70 < np.mean(np.array(picks) == near) < 0.80
    for u in range(4):
        if not planner.expanded[near, u]:
            planner._spend(near, u)
    assert planner._select(target, 8, rng) == far  # exhausted: no longer a candidate


def test_lattice_neighbours_already_in_the_tree_are_spent_on_both_sides():
    ss, planner, gs, edges = make_rcrrt(BoxWorldChecker([]), seed=10)
    prepare(planner)
    a = planner._add_node(np.array([0.5, 0.5]), planner.encode((0, 0)), -1)
    assert planner.untried[a] == 4
    b = planner._add_node(np.array([0.55, 0.5]), planner.encode((1, 0)), a)
    assert planner.expanded[a, 0] and planner.expanded[b, 1]  # a→+x reaches b, b→−x reaches a
    assert planner.untried[a] == 3 and planner.untried[b] == 3
    corner = planner._add_node(np.array([1.0, 0.0]), planner.encode((10, -10)), a)
    assert planner.expanded[corner, 0] and planner.expanded[corner, 3]  # +x and −y leave the limits
    assert planner.untried[corner] == 2


def test_best_input_moves_toward_the_sample():
    ss, planner, gs, edges = make_rcrrt(BoxWorldChecker([]), seed=9)
    prepare(planner)
    i = planner._add_node(np.array([0.5, 0.5]), planner.encode((0, 0)), -1)
    assert planner.best_input(i, np.array([0.5, 0.9])) == 2  # +y
    planner._spend(i, 2)
    assert planner.best_input(i, np.array([0.5, 0.9])) in (0, 1)  # +y spent: a sideways step


def test_same_seed_same_path_and_planner_data():
    paths = []
    for _ in range(2):
        ss, planner, gs, edges = make_rcrrt(maze_checker(), seed=11)
        solve(ss)
        paths.append(solution(ss, gs))
        data = ob.PlannerData(ss.getSpaceInformation())
        planner.getPlannerData(data)
        assert data.numVertices() == planner.count
        assert data.numEdges() == planner.count - 1
        assert planner.graph_size() == (data.numVertices(), data.numEdges())
        assert data.numStartVertices() == 1 and data.numGoalVertices() == 1
    assert np.array_equal(paths[0], paths[1])


def test_honours_the_termination_condition():
    ss, planner, gs, edges = make_rcrrt(closed_maze_checker(), step=0.005, seed=12)
    status = ss.solve(ob.timedPlannerTerminationCondition(0.2))
    assert not ss.haveExactSolutionPath()
    assert not planner.exhausted and planner.failure_proof() is None
    assert status.getStatus() == ob.PlannerStatus.TIMEOUT


def test_named_parameters():
    ss, planner, gs, edges = make_rcrrt(maze_checker())
    params = planner.params()
    assert set(params.param_names()) == {"step", "goal_bias", "candidates", "goal_range", "seed"}
    params.set_param("goal_bias", 0.3)
    assert params.get_param("goal_bias") == 0.3
    with pytest.raises(InvalidRequest, match="no parameter"):
        params.set_param("bogus", 1)
    with pytest.raises(InvalidRequest, match="step"):
        params.set_param("step", 0.0)
    with pytest.raises(InvalidRequest, match="goal_bias"):
        params.set_param("goal_bias", 1.5)
    with pytest.raises(InvalidRequest, match="candidates"):
        params.set_param("candidates", 2.5)
    assert params.get_param("goal_bias") == 0.3 and params.get_param("step") == 0.05
