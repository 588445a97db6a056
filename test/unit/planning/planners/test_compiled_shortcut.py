"""The compiled shortcut (numba, on the sphere checker): every edge it keeps is free by the checker's own answer,
it ends at a path no pair of whose waypoints can be joined, it is deterministic, and it holds its deadline."""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest
from conftest import panda_clutter

from maru_planner.collision.spheres import SphereCollisionChecker
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, postprocess
from maru_planner.planning.planners.compiled_shortcut import shortcut
from maru_planner.planning.space import EdgeChecker, GroupSpace
from maru_planner.scene import Scene
from maru_planner.trajectory import drop_collinear, path_length

ARM = [f"panda_joint{i}" for i in range(1, 8)]
RESOLUTION = 0.05
FOREVER = 1e18


@pytest.fixture(scope="module")
def setting(panda):
    """(edge checker on the arm, raw unsimplified paths) in clutter, confirmation on (near contacts decided exactly)."""
    checker = SphereCollisionChecker(panda, panda_clutter(5, count=12))
    indices = panda.joint_indices(ARM)
    gs = GroupSpace(ARM, indices, panda.lower_limits[indices], panda.upper_limits[indices], panda.neutral())
    planner = MotionPlanner(panda, checker, PlannerConfig(resolution=RESOLUTION, certify=False))
    rng = np.random.default_rng(7)
    free = [q for q in rng.uniform(gs.lower, gs.upper, (400, gs.dim)) if checker.first_invalid(gs.full(q[None])) < 0]
    start, raws = free[0], []
    for seed, goal in enumerate([q for q in free[1:] if np.abs(q - start).max() > 2.0][:6]):
        request = MotionRequest("arm", start=dict(zip(ARM, start, strict=True)),
                                goal_joints=dict(zip(ARM, goal, strict=True)), seed=seed, simplify=False,
                                time_budget=20.0, time_parameterization="trapezoid")  # fmt: skip
        result = planner.plan(request)
        assert result.success, result.message
        raws.append(np.asarray(result.path, dtype=float))
    return EdgeChecker(gs, checker, RESOLUTION), raws


def test_kept_edges_are_free_and_no_pair_of_waypoints_can_be_joined(setting):
    edges, raws = setting
    bent = 0
    for seed, raw in enumerate(raws):
        short = shortcut(raw, edges, seed, FOREVER, 10**6)  # tries without end: it stops when every pair failed
        assert np.array_equal(short[0], raw[0]) and np.array_equal(short[-1], raw[-1])
        assert all(any(np.array_equal(q, r) for r in raw) for q in short)  # waypoints of the raw path
        assert all(edges.edge_valid(a, b) for a, b in zip(short[:-1], short[1:], strict=True))
        assert path_length(short) <= path_length(raw) + 1e-12
        for i, j in itertools.combinations(range(len(short)), 2):
            if j - i >= 2:
                assert not edges.edge_valid(short[i], short[j])
        bent += len(short) > 2
    assert bent  # some path could not be one straight edge: the pairs were really tried


def test_python_shortcut_also_ends_when_every_pair_failed(setting):
    edges, raws = setting
    for seed, raw in enumerate(raws):
        short, _checks = postprocess.shortcut(raw, edges.edge_valid, np.random.default_rng(seed), FOREVER, 10**6)
        assert all(edges.edge_valid(a, b) for a, b in zip(short[:-1], short[1:], strict=True))
        for i, j in itertools.combinations(range(len(short)), 2):
            if j - i >= 2:
                assert not edges.edge_valid(short[i], short[j])


def test_ambiguous_states_go_to_the_exact_model(setting, monkeypatch):
    edges, raws = setting
    calls = []
    first_invalid = edges.checker.first_invalid
    monkeypatch.setattr(edges.checker, "first_invalid", lambda q: calls.append(len(q)) or first_invalid(q))
    for seed, raw in enumerate(raws):
        shortcut(raw, edges, seed, FOREVER, 10**6)
    assert calls  # near contacts were decided on the exact model


def test_same_seed_same_path_and_the_deadline_holds(setting):
    edges, raws = setting
    raw = max(raws, key=len)
    assert np.array_equal(shortcut(raw, edges, 3, FOREVER, 100), shortcut(raw, edges, 3, FOREVER, 100))
    t0 = time.monotonic()
    late = shortcut(raw, edges, 3, t0, 10**6)  # past its deadline: one batch of tries at most
    assert time.monotonic() - t0 < 5.0
    assert all(edges.edge_valid(a, b) for a, b in zip(late[:-1], late[1:], strict=True))


def test_a_cancel_between_batches_ends_it(setting):
    edges, raws = setting

    class Cancelled(Exception):
        pass

    def cancel() -> None:
        raise Cancelled

    with pytest.raises(Cancelled):
        shortcut(max(raws, key=len), edges, 0, FOREVER, 10**6, cancel)


def test_free_space_leaves_one_edge(panda):
    checker = SphereCollisionChecker(panda, Scene([]))
    indices = panda.joint_indices(ARM)
    gs = GroupSpace(ARM, indices, panda.lower_limits[indices], panda.upper_limits[indices], panda.neutral())
    q0 = gs.base[gs.indices]
    zigzag = np.array([q0, q0 + 0.2, q0 + [0.3, -0.1, 0.1, 0.2, 0.0, 0.1, 0.0], q0 + 0.4])
    short = shortcut(zigzag, EdgeChecker(gs, checker, RESOLUTION), 0, FOREVER, 100)
    assert np.array_equal(short, zigzag[[0, -1]])


def test_the_kernel_warm_up_runs_it(maru1, monkeypatch):
    """The warm-up's plans may leave nothing to shortcut (a straight motion): it shortcuts a bent path itself."""
    from maru_planner.planning.planners import compiled_shortcut
    from maru_planner.runtime import warm_up as warm

    calls = []
    real = compiled_shortcut.shortcut
    monkeypatch.setattr(compiled_shortcut, "shortcut", lambda *args: calls.append(args[0]) or real(*args))
    planner = MotionPlanner.from_scene(maru1, warm.boxes(maru1, 1), PlannerConfig(collision_model="spheres"))
    group = max(maru1.groups, key=lambda name: len(maru1.groups[name]))
    warm.shortcut_bent_path(planner, group, *warm.free_pair(planner, group))
    assert [len(drop_collinear(path)) for path in calls] == [3]
    assert compiled_shortcut.run.signatures  # compiled (or loaded from numba's cache)
    exact = MotionPlanner.from_scene(maru1, None, PlannerConfig(collision_model="exact"))
    warm.shortcut_bent_path(exact, group, *warm.free_pair(exact, group))
    assert len(calls) == 1  # nothing to compile on the exact checker
