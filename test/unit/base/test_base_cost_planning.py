"""Cost-aware planning: A* and SE(2) A* optimal for length + multiplier x cost (brute-force Dijkstra), the
papers' planners unchanged by default, the cost layer as their option, clearance reported exactly."""

from __future__ import annotations

import heapq
import itertools
import json
import math

import numpy as np
import pytest

from maru_planner.base import registry
from maru_planner.base.astar import astar_2d
from maru_planner.base.clearance import (
    distance_transform,
    path_clearance,
    point_distances,
    segment_distance,
    to_cell_units,
)
from maru_planner.base.cli import main
from maru_planner.base.costmap import cost_layer
from maru_planner.base.footprint import disc, rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.se2 import search_layers
from maru_planner.paths import config_path

SQRT2 = math.sqrt(2.0)
HOUSE = str(config_path("maps", "house_250.yaml"))


def dijkstra_2d(blocked, weight, start, goal):
    """Cost of the best 8-connected path without corner cutting, a step costing length x (1 + weight[entered])."""
    h, w = blocked.shape
    best = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if (r, c) == goal:
            return d
        if d > best[(r, c)]:
            continue
        for dr, dc in itertools.product((-1, 0, 1), repeat=2):
            nr, nc = r + dr, c + dc
            if (dr, dc) == (0, 0) or not (0 <= nr < h and 0 <= nc < w) or blocked[nr, nc]:
                continue
            if dr and dc and (blocked[r + dr, c] or blocked[r, c + dc]):
                continue
            nd = d + (SQRT2 if dr and dc else 1.0) * (1.0 + weight[nr, nc])
            if nd < best.get((nr, nc), math.inf):
                best[(nr, nc)] = nd
                heapq.heappush(heap, (nd, (nr, nc)))
    return math.inf


def dijkstra_se2(layers, weight, start, goal, rot_cost):
    """The SE(2) lattice of se2.py by enumeration: moves at one heading, turns in place of rot_cost."""
    num_k, h, w = layers.shape
    best = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, (k, r, c) = heapq.heappop(heap)
        if (k, r, c) == goal:
            return d
        if d > best[(k, r, c)]:
            continue
        moves = []
        for dr, dc in itertools.product((-1, 0, 1), repeat=2):
            nr, nc = r + dr, c + dc
            if (dr, dc) == (0, 0) or not (0 <= nr < h and 0 <= nc < w) or layers[k, nr, nc]:
                continue
            if dr and dc and (layers[k, r + dr, c] or layers[k, r, c + dc]):
                continue
            moves.append(((k, nr, nc), (SQRT2 if dr and dc else 1.0) * (1.0 + weight[nr, nc])))
        for nk in ((k + 1) % num_k, (k - 1) % num_k):
            if not layers[nk, r, c]:
                moves.append(((nk, r, c), rot_cost))
        for state, step in moves:
            if d + step < best.get(state, math.inf):
                best[state] = d + step
                heapq.heappush(heap, (d + step, state))
    return math.inf


@pytest.mark.parametrize("seed", range(6))
def test_weighted_astar_is_optimal(seed):
    rng = np.random.default_rng(seed)
    blocked = rng.random((24, 30)) < 0.25
    weight = rng.random((24, 30)) * rng.choice([0.5, 3.0, 20.0])
    free = np.argwhere(~blocked)
    for _ in range(5):
        s, g = (tuple(int(v) for v in free[i]) for i in rng.choice(len(free), 2, replace=False))
        out = astar_2d(blocked, s, g, cell_weight=weight)
        expected = dijkstra_2d(blocked, weight, s, g)
        assert out.cost == pytest.approx(expected, abs=1e-9)
        if len(out.path):  # the path's own cost is the reported one
            steps = np.abs(np.diff(out.path, axis=0)).sum(axis=1)
            own = np.sum(np.where(steps == 2, SQRT2, 1.0) * (1.0 + weight[out.path[1:, 0], out.path[1:, 1]]))
            assert own == pytest.approx(out.cost)


@pytest.mark.parametrize("seed", range(12))
def test_weighted_astar_is_optimal_on_cost_layers(seed):
    """The weights of real cost layers: zero away from obstacles, a band of decaying costs near them."""
    rng = np.random.default_rng(50 + seed)
    size = (int(rng.integers(15, 40)), int(rng.integers(15, 40)))
    occupied = rng.random(size) < rng.choice([0.02, 0.06, 0.15])
    grid = OccupancyGrid(occupied, 1.0)
    inflation = float(rng.choice([1.5, 3.0, 5.0]))
    layer = cost_layer(grid, 0.0, 0.0, inflation, float(rng.choice([0.3, 1.0, 3.0])))
    weight = layer.traversal_weights(float(rng.choice([1.0, 5.0, 50.0])))
    assert (weight == 0).any() and (weight > 0).any()
    free = np.argwhere(~occupied)
    for _ in range(8):
        s, g = (tuple(int(v) for v in free[i]) for i in rng.choice(len(free), 2, replace=False))
        out = astar_2d(occupied, s, g, cell_weight=weight)
        assert out.cost == pytest.approx(dijkstra_2d(occupied, weight, s, g), abs=1e-9)
        if len(out.path):  # the traced path is 8-connected and costs what was reported
            steps = np.abs(np.diff(out.path, axis=0))
            assert steps.max() <= 1
            own = np.sum(
                np.where(steps.sum(axis=1) == 2, SQRT2, 1.0) * (1.0 + weight[out.path[1:, 0], out.path[1:, 1]])
            )
            assert own == pytest.approx(out.cost)


@pytest.mark.parametrize("seed", range(4))
def test_weighted_se2_search_is_optimal(seed):
    rng = np.random.default_rng(seed)
    layers = rng.random((6, 12, 14)) < 0.2
    weight = rng.random((12, 14)) * 5.0
    free = np.argwhere(~layers)
    for _ in range(4):
        s, g = (tuple(int(v) for v in free[i]) for i in rng.choice(len(free), 2, replace=False))
        out = search_layers(layers, [s], g[1:], g[0], 0.7, cell_weight=weight)
        expected = dijkstra_se2(layers, weight, s, g, 0.7)
        assert out.cost == pytest.approx(expected, abs=1e-9)


def corridor() -> OccupancyGrid:
    """A 3 m wide corridor with a pillar: the shortest path grazes the pillar, a cost-aware one keeps off."""
    occupied = np.zeros((30, 80), bool)
    occupied[0, :] = occupied[-1, :] = True
    occupied[12:18, 38:42] = True
    return OccupancyGrid(occupied, 0.1)


@pytest.mark.parametrize("planner_id", ["astar", "se2"])
def test_cost_aware_paths_keep_their_distance(planner_id):
    grid, robot = corridor(), disc(0.2)
    start, goal = (0.5, 1.45, 0.0), (7.5, 1.55, 0.0)
    extra = {"headings": 8} if planner_id == "se2" else {}
    plain = registry.plan(planner_id, grid, start, goal, robot, cost_travel_multiplier=0.0, **extra)
    aware = registry.plan(planner_id, grid, start, goal, robot, inflation_radius=1.0, cost_scaling_factor=3.0, **extra)
    assert plain.success and aware.success, (plain.message, aware.message)
    near, far = path_clearance(grid, plain.path), path_clearance(grid, aware.path)
    assert far.min_m > near.min_m + 0.1
    assert aware.path_length() < 1.2 * plain.path_length()
    assert "costmap" in aware.layers and "costmap" not in plain.layers


def test_plain_astar_is_the_shortest_path_jps_finds():
    grid = corridor()
    result = registry.plan("astar", grid, (0.5, 1.45, 0.0), (7.5, 1.55, 0.0), disc(0.2), cost_travel_multiplier=0.0)
    grown = grid.inflate(0.2).occupied
    reference = astar_2d(grown, grid.world_to_cell(0.5, 1.45), grid.world_to_cell(7.5, 1.55))
    assert result.stats.cost == pytest.approx(reference.cost * 0.1)


@pytest.mark.parametrize("planner_id", ["mspp", "mspp_local", "tunnel"])
def test_papers_planners_are_unchanged_by_default(planner_id):
    spec = registry.spec(planner_id)
    assert spec.params["cost_travel_multiplier"].default == 0.0 and spec.params["smooth"].default is False
    grid = corridor()
    result = registry.plan(planner_id, grid, (0.5, 1.45, 0.0), (7.5, 1.55, 0.0), rectangle(0.4, 0.3))
    assert result.success and "costmap" not in result.layers


@pytest.mark.parametrize("planner_id", ["mspp", "tunnel"])
def test_papers_planners_take_the_cost_layer_as_an_option(planner_id):
    grid, robot = corridor(), disc(0.2)
    start, goal = (0.5, 1.45, 0.0), (7.5, 1.55, 0.0)
    plain = registry.plan(planner_id, grid, start, goal, robot)
    aware = registry.plan(
        planner_id, grid, start, goal, robot, cost_travel_multiplier=5.0, inflation_radius=1.0, cost_scaling_factor=3.0
    )
    assert aware.success and "costmap" in aware.layers
    assert path_clearance(grid, aware.path).min_m >= path_clearance(grid, plain.path).min_m - 1e-9


def test_every_grid_planner_declares_the_cost_parameters():
    names = {"inflation_radius", "cost_scaling_factor", "cost_travel_multiplier", "smooth", "min_turning_radius"}
    for planner_id in ("astar", "se2", "mspp", "mspp_local", "tunnel"):
        params = registry.spec(planner_id).params
        assert names <= set(params), planner_id
        assert params["cost_scaling_factor"].default == 10.0 and params["inflation_radius"].default is None
    assert registry.spec("astar").params["cost_travel_multiplier"].default == 2.0
    assert "robot_radius" in registry.spec("astar").params  # the obstacle growth, as Nav2 names a disc robot


def test_exact_clearance_against_enumeration():
    rng = np.random.default_rng(11)
    occupied = rng.random((40, 50)) < 0.05
    grid = OccupancyGrid(occupied, 0.1, (-1.0, 0.5, 0.3))
    edt = distance_transform(occupied)
    centres = np.argwhere(occupied) + 0.5
    points = rng.random((500, 2)) * [40, 50]
    brute = np.min(np.linalg.norm(points[:, None] - centres[None], axis=2), axis=1)
    assert np.allclose(point_distances(occupied, edt, points), brute)
    a, b = points[0], points[0] + [7.3, -4.1]
    t = np.linspace(0, 1, 20001)[:, None]
    dense = np.min(np.linalg.norm((a + t * (b - a))[:, None] - centres[None], axis=2))
    assert segment_distance(occupied, a, b, 1e9) == pytest.approx(dense, abs=1e-4)
    assert segment_distance(occupied, a, b, 1e9) <= dense + 1e-12
    xy = grid.cells_to_world(np.array([[3, 4], [20, 30]]))
    clearance = path_clearance(grid, xy)
    cells = to_cell_units(grid, xy)
    assert clearance.min_m == pytest.approx(segment_distance(occupied, cells[0], cells[1], 1e9) * 0.1)


@pytest.mark.parametrize("planner_id", [p for p in registry.planner_ids() if not p.startswith("biped")])
def test_cli_json_reports_clearance_for_every_grid_planner(tmp_path, planner_id):
    out = tmp_path / "plan.json"
    headings = ["--param", "headings=8"] if registry.spec(planner_id).has(registry.NEEDS_HEADINGS) else []
    code = main(
        [
            "--map",
            HOUSE,
            "--planner",
            planner_id,
            "--start",
            "2.5",
            "21",
            "0",
            "--goal",
            "22",
            "3",
            "0",
            "--footprint",
            "disc:0.3",
            "--json",
            str(out),
            *headings,
        ]
    )
    data = json.loads(out.read_text())
    assert code == 0, data["message"]
    assert set(data["clearance"]) == {"min_m", "mean_m"}
    assert 0.3 < data["clearance"]["min_m"] <= data["clearance"]["mean_m"]


@pytest.mark.parametrize("planner_id", ["biped_track", "biped_wall"])
def test_cli_json_reports_clearance_for_the_biped_planners(tmp_path, planner_id):
    out = tmp_path / "plan.json"
    code = main(
        [
            "--world",
            str(config_path("worlds", "biped", "corridor_wide.yaml")),
            "--planner",
            planner_id,
            "--json",
            str(out),
        ]
    )
    data = json.loads(out.read_text())
    assert code == 0, data["message"]
    assert data["clearance"]["min_m"] > 0 and data["clearance"]["mean_m"] >= data["clearance"]["min_m"]


def test_failed_plan_has_no_clearance(tmp_path):
    out = tmp_path / "plan.json"
    main(
        [
            "--map",
            str(config_path("maps", "paper002_impossible.yaml")),
            "--start",
            "1",
            "2",
            "0",
            "--goal",
            "5",
            "2",
            "0",
            "--json",
            str(out),
        ]
    )
    assert json.loads(out.read_text())["clearance"] is None
