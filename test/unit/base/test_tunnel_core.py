"""Tunnel planner (paper 003) on plain bool grids: completeness against connectivity, safety, determinism."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import ndimage

from maru_planner.base.result import PlanStatus as res
from maru_planner.base.tunnel import TunnelParams, TunnelPlanner, lumped_cells, segment_is_free


def random_map(n: int, seed: int, boxes: int | None = None) -> np.ndarray:
    rng = np.random.default_rng(seed)
    occ = np.zeros((n, n), dtype=bool)
    for _ in range(boxes if boxes is not None else n // 2):
        r, c = rng.integers(0, n, 2)
        h, w = rng.integers(1, max(2, n // 8), 2)
        occ[r : r + h, c : c + w] = True
    return occ


def random_query(occ: np.ndarray, seed: int):
    free = np.argwhere(~occ)
    rng = np.random.default_rng(seed + 1000)
    return tuple(free[rng.integers(len(free))]), tuple(free[rng.integers(len(free))])


def connected(occ, s, g) -> bool:
    labels, _ = ndimage.label(~occ)  # 4-connectivity = 8-connectivity without corner cutting
    return labels[s] == labels[g]


def dense_path_is_free(occ: np.ndarray, cells: np.ndarray) -> bool:
    """Independent check: sample each segment every 1/20 cell, plus both cells at exact corner crossings."""
    for a, b in zip(cells[:-1], cells[1:]):
        n = 20 * int(max(abs(b - a))) + 2
        t = np.linspace(0, 1, n)[:, None]
        pts = a + 0.5 + t * (b - a)
        idx = np.floor(pts).astype(int)
        if occ[idx[:, 0], idx[:, 1]].any():
            return False
    return True


MAPS = [(n, seed) for seed in range(24) for n in (24, 40, 64)][:48]


@pytest.mark.parametrize("n,seed", MAPS)
def test_finds_a_path_exactly_when_one_exists_and_never_through_obstacles(n, seed):
    occ = random_map(n, seed)
    s, g = random_query(occ, seed)
    plan = TunnelPlanner().plan_cells(occ, s, g)
    assert (plan.status == res.SOLVED) == connected(occ, s, g), plan.message
    if plan.status == res.SOLVED:
        raw = plan.raw_cells
        assert tuple(raw[0]) == s and tuple(raw[-1]) == g
        assert not occ[raw[:, 0], raw[:, 1]].any()
        steps = np.abs(np.diff(raw, axis=0))
        assert steps.max() <= 1 and (steps.sum(axis=1) > 0).all()
        for (r0, c0), (r1, c1) in zip(raw[:-1], raw[1:]):
            if r0 != r1 and c0 != c1:
                assert not occ[r1, c0] and not occ[r0, c1], "corner cut"
        assert dense_path_is_free(occ, plan.waypoints)
        assert tuple(plan.waypoints[0]) == s and tuple(plan.waypoints[-1]) == g


def test_deterministic():
    occ = random_map(64, 7)
    s, g = random_query(occ, 7)
    a = TunnelPlanner().plan_cells(occ, s, g)
    b = TunnelPlanner().plan_cells(occ, s, g)
    assert a.status == b.status
    np.testing.assert_array_equal(a.raw_cells, b.raw_cells)
    np.testing.assert_array_equal(a.waypoints, b.waypoints)
    assert dataclasses.replace(a.stats, planning_time=0.0) == dataclasses.replace(b.stats, planning_time=0.0)


def test_thin_tunnel_has_no_lumped_cells_and_is_a_chain():
    occ = np.zeros((60, 60), dtype=bool)
    occ[10:50, 30] = True  # a wall the greedy walk runs into: it spreads before going round
    plan = TunnelPlanner().plan_cells(occ, (30, 5), (30, 55))
    assert plan.status == res.SOLVED
    attempt = plan.attempts[-1]
    thin = [tuple(b) for b in attempt.thin_tunnel]
    assert lumped_cells(thin) == []
    for a, b in zip(thin[:-1], thin[1:]):
        assert abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1
    assert len(attempt.tunnel) >= len(thin)
    assert set(thin) <= {tuple(b) for b in attempt.tunnel}


def test_lumped_cells_detects_three_neighbours():
    blob = [(0, 0), (0, 1), (1, 0), (1, 1), (2, 1)]
    assert lumped_cells(blob) == [(1, 1)]
    assert lumped_cells([(0, 0), (0, 1), (0, 2)]) == []


def _wall_map():
    # 6 × 9 cells = 2 × 3 big cells of 3 × 3. A wall in column 4 cuts the upper big-cell row.
    occ = np.zeros((6, 9), dtype=bool)
    occ[0:3, 4] = True
    return occ


def test_virtual_obstacle_at_minimum_size_reroutes_the_tunnel():
    plan = TunnelPlanner(big_cell_size=3, min_big_cell_size=3).plan_cells(_wall_map(), (0, 0), (0, 8))
    assert plan.status == res.SOLVED
    assert plan.stats.virtual_obstacles == 1
    first, last = plan.attempts[0], plan.attempts[-1]
    assert first.failed_stage == "PFP" and last.failed_stage is None
    assert ((0, 1), (0, 2)) in last.virtual_obstacles


def test_shrinks_big_cells_when_path_finding_fails():
    plan = TunnelPlanner(big_cell_size=3, min_big_cell_size=1).plan_cells(_wall_map(), (0, 0), (0, 8))
    assert plan.status == res.SOLVED
    sizes = [a.big_cell_size for a in plan.attempts]
    assert sizes[0] == 3 and sizes == sorted(sizes, reverse=True) and len(sizes) >= 2


def test_reports_no_path_honestly_when_the_wall_is_closed():
    occ = np.zeros((3, 9), dtype=bool)
    occ[:, 4] = True
    for minimum in (1, 3):
        plan = TunnelPlanner(min_big_cell_size=minimum).plan_cells(occ, (1, 0), (1, 8))
        assert plan.status == res.NO_PATH
        assert len(plan.raw_cells) == 0
        assert "TFP" in plan.message


def test_start_and_goal_checks():
    occ = np.zeros((9, 9), dtype=bool)
    occ[4, 4] = True
    planner = TunnelPlanner()
    assert planner.plan_cells(occ, (4, 4), (0, 0)).status == res.START_OCCUPIED
    assert planner.plan_cells(occ, (0, 0), (4, 4)).status == res.GOAL_OCCUPIED
    assert planner.plan_cells(occ, (-1, 0), (0, 0)).status == res.START_OUTSIDE_MAP
    assert planner.plan_cells(occ, (0, 0), (0, 9)).status == res.GOAL_OUTSIDE_MAP
    same = planner.plan_cells(occ, (0, 0), (0, 0))
    assert same.status == res.SOLVED and len(same.raw_cells) == 1


@pytest.mark.parametrize(
    "bad",
    [
        {"k1": 0.0},
        {"k2": 0.1},
        {"k3": -1.0},
        {"k4": -1.0},
        {"k5": 0.0},
        {"big_cell_size": 0},
        {"min_big_cell_size": 4},
        {"no_such": 1},
    ],
)
def test_parameter_signs_follow_the_paper(bad):
    with pytest.raises(ValueError):
        TunnelPlanner(**bad)


def test_params_dataclass_defaults_are_valid():
    TunnelParams().validate()


def test_segment_check_is_conservative_at_corners():
    occ = np.zeros((2, 2), dtype=bool)
    occ[0, 1] = True
    assert not segment_is_free(occ, (0, 0), (1, 1))  # a diagonal grazing an occupied corner cell
    assert segment_is_free(occ, (1, 0), (1, 1))
