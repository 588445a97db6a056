"""OMPL glue, post-processing and the MotionPlanner facade on a 2-D toy robot (no robot model needed)."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from ompl import geometric as og
from planning_toys import BoxWorldChecker, ToyRobot, maze_checker

from maru_planner import errors
from maru_planner.planning import (
    PLANNERS,
    MotionPlanner,
    MotionRequest,
    PlannerConfig,
    PlanStatus,
    planner_ids,
    postprocess,
)
from maru_planner.planning.space import BatchedMotionValidator, EdgeChecker, GroupSpace, edge_states
from maru_planner.planning.types import status_of_error
from maru_planner.trajectory import deviation_from_path, drop_collinear, path_length, smoothness, time_parameterize

START = {"j0": 0.05, "j1": 0.05}
GOAL = {"j0": 0.95, "j1": 0.95}


class CountingChecker(BoxWorldChecker):
    def __init__(self, boxes):
        super().__init__(boxes)
        self.batch_calls = 0

    def first_invalid(self, Q):
        self.batch_calls += 1
        return super().first_invalid(Q)


def planner_for(checker=None, **config):
    config.setdefault("resolution", 0.01)
    config.setdefault("planner_params", {"RCRRT": {"step": 0.05}})
    config.setdefault("prm_roadmap_nodes", 300)
    return MotionPlanner(ToyRobot(2), checker or maze_checker(), PlannerConfig(**config))


def request(**kw):
    kw.setdefault("group", "all")
    kw.setdefault("start", dict(START))
    kw.setdefault("goal_joints", dict(GOAL))
    kw.setdefault("planner_id", "RRTConnect")
    kw.setdefault("time_budget", 3.0)
    kw.setdefault("seed", 1)
    return MotionRequest(**kw)


# --- glue ------------------------------------------------------------------------------------
def test_edge_states_respect_the_resolution():
    qa, qb = np.array([0.0, 0.0]), np.array([0.33, -0.1])
    Q = edge_states(qa, qb, 0.02)
    assert np.allclose(Q[-1], qb)
    steps = np.abs(np.diff(np.vstack([qa, Q]), axis=0))
    assert steps.max() <= 0.02 + 1e-12
    assert len(Q) == 17  # ceil(0.33 / 0.02)


def test_group_space_fills_joints_outside_the_group():
    gs = GroupSpace(["b"], [1], [-1], [1], [0.3, 0.0, 0.7])
    assert np.allclose(gs.full(np.array([0.5])), [0.3, 0.5, 0.7])
    assert np.allclose(gs.full(np.array([[0.1], [0.2]])), [[0.3, 0.1, 0.7], [0.3, 0.2, 0.7]])
    assert gs.space.getBounds().low[0] == -1


def test_motion_validator_checks_an_edge_in_one_batched_call():
    checker = CountingChecker([((0.4, 0.4), (0.6, 0.6))])
    gs = GroupSpace(["x", "y"], [0, 1], [0, 0], [1, 1], [0, 0])
    edges = EdgeChecker(gs, checker, 0.01)
    ss = og.SimpleSetup(gs.space)
    validator = BatchedMotionValidator(ss.getSpaceInformation(), edges)
    assert not validator.checkMotion(gs.to_state([0.1, 0.1]), gs.to_state([0.9, 0.9]))
    assert validator.checkMotion(gs.to_state([0.1, 0.1]), gs.to_state([0.9, 0.1]))
    assert checker.batch_calls == 2


# --- post-processing -------------------------------------------------------------------------
def test_shortcut_stays_collision_free_and_shortens():
    checker = maze_checker()
    gs = GroupSpace(["x", "y"], [0, 1], [0, 0], [1, 1], [0, 0])
    edges = EdgeChecker(gs, checker, 0.01)
    zigzag = np.array([[0.05, 0.05], [0.1, 0.9], [0.12, 0.85], [0.15, 0.9], [0.4, 0.9], [0.42, 0.1], [0.45, 0.15]])
    assert edges.path_valid(zigzag)
    short, checks = postprocess.shortcut(zigzag, edges.edge_valid, np.random.default_rng(0), 1e18, 50)
    assert checks > 0
    assert edges.path_valid(short)
    assert path_length(short) < path_length(zigzag)
    assert np.allclose(short[0], zigzag[0]) and np.allclose(short[-1], zigzag[-1])


def test_drop_collinear_keeps_the_corners_and_the_ends_only():
    """Waypoints on the line between their neighbours go (also several in a row: the test is against the last
    waypoint kept, not the dropped one); corners and both ends stay."""
    corner = np.array([[0, 0], [1, 0], [1.5, 0], [2, 0], [2, 1], [2, 1.5], [2, 3]], float)
    assert drop_collinear(corner).tolist() == [[0, 0], [2, 0], [2, 3]]
    back = np.array([[0, 0], [2, 0], [1, 0]], float)  # turning back on the line is a corner
    assert drop_collinear(back).tolist() == back.tolist()
    rng = np.random.default_rng(0)
    for _ in range(200):  # a random polyline with points inserted on its segments: the polyline comes back
        path = rng.normal(size=(int(rng.integers(2, 8)), 5))
        dense = [path[0]]
        for a, b in zip(path[:-1], path[1:], strict=True):
            dense += [a + t * (b - a) for t in np.sort(rng.choice([0.25, 0.5, 0.9], size=2, replace=False))] + [b]
        assert np.allclose(drop_collinear(np.array(dense)), path)


def test_drop_collinear_keeps_a_waypoint_farther_than_max_offset_from_its_line():
    """The angle test lets a waypoint 1e-6 rad off a 2 rad line go; ``max_offset`` (1e-9 rad by default) keeps it,
    and not the waypoints on the lines to it; small turns do not add up to a dropped bend."""
    path = np.array([[0, 0], [0.5, 0.5e-6], [1, 1e-6], [1.5, 0.5e-6], [2, 0]], float)
    assert drop_collinear(path).tolist() == path[[0, 2, 4]].tolist()
    assert len(drop_collinear(path, max_offset=1e-5)) == 2
    arc = np.stack([np.cos(np.linspace(0, 0.04, 1001)), np.sin(np.linspace(0, 0.04, 1001))], axis=1)  # 4e-5 a step
    kept = drop_collinear(arc)
    assert 2 < len(kept) < len(arc) and deviation_from_path(arc, kept).max() <= 1e-9


def test_time_parameterisation_respects_scaled_limits():
    path = np.array([[0.0, 0.0], [1.0, 0.2], [1.0, 1.2], [1.01, 1.2]])
    vmax, amax = np.array([1.0, 0.5]), np.array([2.0, 1.0])
    traj = time_parameterize(path, ["a", "b"], vmax, amax, 0.5, 0.25, dt=0.01)
    assert np.all(np.diff(traj.times) > 0)
    assert np.allclose(traj.positions[0], path[0]) and np.allclose(traj.positions[-1], path[-1])
    assert np.all(np.abs(traj.velocities) <= vmax * 0.5 + 1e-9)
    assert np.all(np.abs(traj.accelerations) <= amax * 0.25 + 1e-9)
    assert np.allclose(traj.velocities[-1], 0.0)
    for q in path:  # every waypoint is passed exactly
        assert np.min(np.linalg.norm(traj.positions - q, axis=1)) < 1e-9
    # finite differences agree with the reported velocities
    fd = np.diff(traj.positions, axis=0) / np.diff(traj.times)[:, None]
    mid = 0.5 * (traj.velocities[1:] + traj.velocities[:-1])
    assert np.max(np.abs(fd - mid)) < 0.05


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.lists(st.lists(st.sampled_from([0.0, 1e-13, 1e-3, 0.3, -1.0, 2.5]), min_size=3, max_size=3), min_size=1,
                max_size=8),
       st.sampled_from([0.001, 0.05, 0.5]), st.sampled_from([2, 7, 10_000]))  # fmt: skip
def test_trapezoids_keep_the_limits_stop_at_every_waypoint_and_cap_their_samples(steps, dt, max_points):
    """Any path (repeated and near-repeated waypoints too): increasing times from 0, each waypoint passed exactly at
    rest, the scaled limits kept, at most max_points samples plus one per segment."""
    path = np.cumsum(np.array(steps, float), axis=0)
    vmax, amax = np.array([1.0, 0.5, 2.0]), np.array([2.0, 1.0, 4.0])
    traj = time_parameterize(path, ["a", "b", "c"], vmax, amax, 0.5, 0.25, dt=dt, max_points=max_points)
    assert traj.times[0] == 0.0 and np.all(np.diff(traj.times) > 0)
    assert len(traj.times) <= max_points + len(path)
    assert np.all(np.abs(traj.velocities) <= 0.5 * vmax + 1e-9)
    assert np.all(np.abs(traj.accelerations) <= 0.25 * amax + 1e-9)
    moving = np.abs(np.diff(path, axis=0)).max(axis=1, initial=0.0) > 1e-12
    for k in np.flatnonzero(moving):  # the move to each waypoint ends on it exactly, at rest
        at = np.flatnonzero((traj.positions == path[k + 1]).all(axis=1))
        assert len(at) and np.allclose(traj.velocities[at[-1]], 0.0, atol=1e-12)
    end = path[np.flatnonzero(moving)[-1] + 1] if moving.any() else path[0]  # a last step under 1e-12 rad: not taken
    assert np.array_equal(traj.positions[-1], end)


def test_smoothness_is_zero_for_a_straight_line_and_positive_for_a_corner():
    assert smoothness(np.array([[0, 0], [1, 0], [2, 0]], float)) == 0.0
    assert smoothness(np.array([[0, 0], [1, 0], [1, 1]], float)) == pytest.approx(np.pi**2 / 4)  # (2·½π/2)²
    # as OMPL's: triples with a repeated waypoint count nothing (here the corner at it), the 90° turn over segments
    # of 1 and 2 after it counts (2·½π/3)²
    square = np.array([[0, 0], [1, 0], [1, 0], [1, 1], [-1, 1]], float)
    assert smoothness(square) == pytest.approx(np.pi**2 / 9)


# --- facade: every planner -------------------------------------------------------------------
def params_that_finish() -> dict[str, dict]:
    """Per-planner parameters with which every registered planner can reach the maze's goal:
    a planner whose goal bias defaults to 0 (plain RRT) never lands exactly on the goal."""
    params = {
        pid: {"goal_bias": 0.05}
        for pid, spec in PLANNERS.items()
        if "goal_bias" in spec.params and spec.params["goal_bias"].default == 0
    }
    return {**params, "RCRRT": {"step": 0.05}}


@pytest.mark.parametrize("planner_id", planner_ids())
def test_every_planner_solves_the_maze(planner_id):
    mp = planner_for(planner_params=params_that_finish())
    res = mp.plan(request(planner_id=planner_id, time_budget=20.0))  # success, not speed: room for a loaded machine
    assert res.status is PlanStatus.SUCCESS, res.message
    assert res.success
    assert res.joint_names == ["j0", "j1"]
    assert np.allclose(res.path[0], [0.05, 0.05]) and np.allclose(res.path[-1], [0.95, 0.95])
    gs = GroupSpace(["j0", "j1"], [0, 1], [0, 0], [1, 1], [0.5, 0.5])
    assert EdgeChecker(gs, maze_checker(), 0.01).path_valid(res.path)
    s = res.stats
    assert s.planner_id == planner_id and s.nodes > 0 and s.collision_checks > 0
    assert s.waypoints == len(res.path) and s.path_length > 0 and s.total_time >= s.solve_time > 0
    assert res.trajectory.positions.shape[1] == 2
    js = res.to_json_dict()
    assert set(js) == {"success", "status", "message", "joint_names", "path", "trajectory", "stats", "seed"}
    assert js["status"] == "SUCCESS" and js["seed"] == 1


def test_plain_rrt_without_goal_bias_reports_a_timeout():
    res = planner_for().plan(request(planner_id="RRT", time_budget=0.3))
    assert res.status is PlanStatus.TIMED_OUT
    assert "RRT" in res.message and isinstance(res.error, errors.PlanningTimedOut)


@pytest.mark.parametrize("planner_id", planner_ids())
def test_same_seed_same_path(planner_id):
    """Two seeds, each planned by two fresh planners (a roadmap is built anew each time) and again
    by the first one (a tree planner starts from scratch every query): the paths are identical."""
    for seed in (5, 6):
        first = planner_for(planner_params=params_that_finish())
        a = first.plan(request(planner_id=planner_id, seed=seed))
        b = planner_for(planner_params=params_that_finish()).plan(request(planner_id=planner_id, seed=seed))
        assert a.success and b.success, (a.message, b.message)
        assert np.array_equal(a.path, b.path)
        if not PLANNERS[planner_id].has("roadmap"):
            assert np.array_equal(first.plan(request(planner_id=planner_id, seed=seed)).path, a.path)


def test_rcrrt_reports_no_path_at_its_resolution():
    from planning_toys import closed_maze_checker

    res = planner_for(closed_maze_checker()).plan(request(planner_id="RCRRT", time_budget=20.0))
    assert res.status is PlanStatus.PLANNING_FAILED
    assert "no path exists at step 0.05" in res.message


# --- facade: fail-fast pre-checks ------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, status, words",
    [
        ({"group": "legs"}, PlanStatus.INVALID_GROUP, "legs"),
        ({"planner_id": "AStar"}, PlanStatus.INVALID_PLANNER, "AStar"),
        ({"start": {"j0": 0.1, "knee": 0.2}}, PlanStatus.INVALID_JOINT_NAMES, "knee"),
        ({"start": {"j0": 0.1}}, PlanStatus.INVALID_JOINT_NAMES, "j1"),
        ({"goal_joints": {"j0": 0.9}}, PlanStatus.INVALID_JOINT_COUNT, "j1"),
        ({"goal_joints": {"j0": float("nan"), "j1": 0.9}}, PlanStatus.INVALID_STATE, "j0"),
        ({"start": {"j0": 0.05, "j1": 1.5}}, PlanStatus.INVALID_STATE, "j1 = 1.5000 is outside"),
        ({"start": {"j0": 0.25, "j1": 0.05}}, PlanStatus.START_IN_COLLISION, "box0"),
        ({"goal_joints": {"j0": 0.55, "j1": 0.5}}, PlanStatus.GOAL_IN_COLLISION, "box1"),
        ({"start": None}, PlanStatus.NO_START_STATE, "start"),
        ({"goal_joints": None}, PlanStatus.INVALID_REQUEST, "goal"),
        ({"time_budget": 0.0}, PlanStatus.INVALID_REQUEST, "time_budget"),
        ({"time_budget": float("inf")}, PlanStatus.INVALID_REQUEST, "time_budget"),
        ({"attempts": 0}, PlanStatus.INVALID_REQUEST, "attempts"),
        ({"velocity_scaling": 1.5}, PlanStatus.INVALID_REQUEST, "velocity_scaling"),
        ({"goal_poses": {"tool": np.eye(4)}}, PlanStatus.INVALID_REQUEST, "either"),
    ],
)
def test_bad_requests_fail_fast_with_a_code_and_message(kwargs, status, words):
    checker = maze_checker()
    res = planner_for(checker).plan(request(**kwargs))
    assert res.status is status, res.message
    assert words in res.message
    assert not res.success and res.path is None
    assert res.error is not None and status_of_error(res.error) is status
    if status is PlanStatus.START_IN_COLLISION:
        assert res.error.pairs == [("robot", "box0")]


def test_a_broken_checker_is_reported_not_raised():
    class Broken(BoxWorldChecker):
        def first_invalid(self, Q):
            raise RuntimeError("checker exploded")

    res = planner_for(Broken([])).plan(request())
    assert res.status is PlanStatus.PLANNING_FAILED and "checker exploded" in res.message


def test_start_equal_goal_is_a_trivial_success():
    res = planner_for().plan(request(goal_joints=dict(START)))
    assert res.success and len(res.path) == 2 and res.trajectory.duration == 0.0


# --- PRM roadmap reuse -----------------------------------------------------------------------
class Scene:
    def __init__(self, boxes):
        self.boxes = boxes


def test_prm_roadmap_is_reused_and_revalidated_after_a_scene_change():
    walls = maze_checker().boxes
    mp = planner_for(BoxWorldChecker(walls))
    first = mp.plan(request(planner_id="PRM"))
    assert first.success and first.stats.roadmap_build_time > 0 and not first.stats.roadmap_reused
    second = mp.plan(request(planner_id="PRM", goal_joints={"j0": 0.95, "j1": 0.5}, seed=2))
    assert second.success and second.stats.roadmap_reused and second.stats.roadmap_build_time == 0.0
    assert second.stats.nodes >= first.stats.nodes
    # An obstacle far from everything: the stale roadmap's answer is verified and kept, no re-validation.
    mp.set_scene(Scene(list(walls) + [((5.0, 5.0), (6.0, 6.0))]))
    third = mp.plan(request(planner_id="PRM", seed=3))
    assert third.success and third.stats.roadmap_reused and third.stats.roadmap_build_time == 0.0
    assert mp.last_revalidation is None
    # A wall closing the left corridor: the stale roadmap's answer is blocked, so the roadmap is
    # re-validated (pieces died) and rebuilt; the goal is now unreachable and no blocked path escapes.
    blocker = ((-0.1, 0.5), (0.2, 0.52))
    assert not EdgeChecker(
        GroupSpace(["j0", "j1"], [0, 1], [0, 0], [1, 1], [0.5, 0.5]), BoxWorldChecker([blocker]), 0.01
    ).path_valid(first.path)
    mp.set_scene(Scene(list(walls) + [blocker]))
    fourth = mp.plan(request(planner_id="PRM", seed=4, time_budget=1.0))
    report = mp.last_revalidation
    assert report is not None and not report.still_valid and report.states_checked > report.vertices
    assert fourth.stats.roadmap_build_time > 0 and not fourth.stats.roadmap_reused
    assert fourth.status is PlanStatus.TIMED_OUT and fourth.path is None


# --- threads ---------------------------------------------------------------------------------
def test_concurrent_plans_from_several_threads():
    mp = planner_for()
    results = {}

    def work(k):
        results[k] = mp.plan(request(planner_id=("RRTConnect", "RCRRT")[k % 2], seed=k))

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert len(results) == 4 and all(r.success for r in results.values())
    again = mp.plan(request(planner_id="RCRRT", seed=1))
    assert np.array_equal(again.path, results[1].path)


def test_roadmap_query_phase_runs_on_the_graph_and_grows_only_when_needed():
    from maru_planner.planning.planners.roadmap import Roadmap

    gs = GroupSpace(["x", "y"], [0, 1], [0, 0], [1, 1], [0.5, 0.5])
    roadmap = Roadmap(gs, maze_checker(), 0.01)
    grown = roadmap.query(np.array([0.05, 0.05]), np.array([0.95, 0.95]), 2.0)  # empty roadmap: OMPL grows it
    assert grown[0] == "grow" and grown[1] is not None
    roadmap.build(300, 1e18)
    size = roadmap.milestones
    mode, path = roadmap.query(np.array([0.1, 0.1]), np.array([0.9, 0.9]), 2.0)
    assert mode == "roadmap" and roadmap.milestones == size  # answered from the graph, nothing added
    assert np.allclose(path[0], [0.1, 0.1]) and np.allclose(path[-1], [0.9, 0.9])
    assert roadmap.edges.path_valid(path)
