"""Nav2's inflation layer on OccupancyGrid (costmap.py): values, exactness, strips, budgets, bad parameters."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from maru_planner.base import registry
from maru_planner.base.budget import Deadline
from maru_planner.base.cli import main
from maru_planner.base.cost_model import CostModel
from maru_planner.base.costmap import (
    INSCRIBED_INFLATED_OBSTACLE,
    LETHAL_OBSTACLE,
    NO_INFORMATION,
    cost_layer,
    cost_of_distance,
    to_occupancy_values,
)
from maru_planner.base.footprint import disc, rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import PlanStatus
from maru_planner.errors import InvalidRequest, PlanningTimedOut
from maru_planner.paths import config_path

MEDIUM = str(config_path("maps", "paper002_medium.yaml"))


def brute_distances(occupied: np.ndarray, resolution: float) -> np.ndarray:
    """Centre-to-centre distance (m) from every cell to the nearest occupied one, by enumeration."""
    obstacles = np.argwhere(occupied)
    cells = np.argwhere(np.ones_like(occupied))
    d = np.min(np.linalg.norm(cells[:, None, :] - obstacles[None, :, :], axis=2), axis=1)
    return d.reshape(occupied.shape) * resolution


def nav2_cost(d: float, inscribed: float, inflation: float, scaling: float) -> int:
    """inflation_layer.hpp computeCost, for one distance in metres."""
    if d == 0:
        return 254
    if d <= inscribed:
        return 253
    if d > inflation:
        return 0
    return int((253 - 1) * math.exp(-scaling * (d - inscribed)))


def test_costs_follow_nav2s_formula():
    distances = np.array([0.0, 0.1, 0.15, 0.2, 0.3, 0.45, 0.55, 0.56, 3.0])
    costs = cost_of_distance(distances, 0.15, 0.55, 10.0)
    assert costs.tolist() == [nav2_cost(d, 0.15, 0.55, 10.0) for d in distances]
    assert costs[0] == LETHAL_OBSTACLE and costs[2] == INSCRIBED_INFLATED_OBSTACLE and costs[-1] == 0


@pytest.mark.parametrize("seed", range(4))
def test_cost_layer_is_exact_against_enumeration(seed):
    rng = np.random.default_rng(seed)
    occupied = rng.random((37, 29)) < 0.04
    occupied[5, 5] = True
    grid = OccupancyGrid(occupied, 0.05, (1.0, 2.0, 0.4))
    layer = cost_layer(grid, 0.12, 0.2, 0.4, 3.0)
    expected = brute_distances(occupied, 0.05)
    within = expected <= 0.4 + 1e-12
    assert np.allclose(layer.distance[within], expected[within])
    assert np.all(np.isinf(layer.distance[~within]))
    wanted = [[nav2_cost(d, 0.12, 0.4, 3.0) for d in row] for row in expected]
    assert layer.cost.tolist() == wanted
    # the lethal cells of a disc are exactly the grid grown by its radius
    assert np.array_equal(layer.lethal(), grid.inflate(0.12).occupied)


def test_strips_give_the_whole_map_answer():
    rng = np.random.default_rng(7)
    occupied = rng.random((700, 90)) < 0.002  # taller than several strips of rows
    grid = OccupancyGrid(occupied, 0.1)
    layer = cost_layer(grid, 0.3, 0.3, 1.2, 2.0)
    from scipy import ndimage

    whole = ndimage.distance_transform_edt(~occupied) * 0.1
    within = whole <= 1.2 + 1e-12
    assert np.array_equal(np.isfinite(layer.distance), within)
    assert np.allclose(layer.distance[within], whole[within])


def test_published_values_are_nav2s_scaling():
    costs = np.array([0, 1, 2, 126, 252, 253, 254, 255], dtype=np.uint8)
    assert to_occupancy_values(costs).tolist() == [0, 1, 1, 49, 98, 99, 100, -1]
    unknown = np.zeros(8, bool)
    unknown[0] = True
    assert to_occupancy_values(costs, unknown).tolist()[0] == -1
    assert NO_INFORMATION == 255


def test_a_4000_square_map_keeps_the_budget():
    occupied = np.zeros((4000, 4000), bool)
    occupied[::97, ::89] = True
    grid = OccupancyGrid(occupied, 0.05)
    t = time.perf_counter()
    with pytest.raises(PlanningTimedOut, match="cost map"):
        cost_layer(grid, 0.2, 0.3, 0.55, 10.0, Deadline(0.05))
    assert time.perf_counter() - t < 1.0
    result = registry.plan("astar", grid, (1.0, 1.0, 0.0), (190.0, 190.0, 0.0), disc(0.2), time_limit=0.5)
    assert result.status is PlanStatus.TIMED_OUT
    assert result.stats.planning_time < 1.0


@pytest.mark.parametrize(
    "params, needle",
    [
        ({"inflation_radius": -0.1}, "inflation_radius"),
        ({"inflation_radius": math.nan}, "inflation_radius"),
        ({"cost_scaling_factor": -1.0}, "cost_scaling_factor"),
        ({"cost_scaling_factor": math.inf}, "cost_scaling_factor"),
        ({"cost_travel_multiplier": -2.0}, "cost_travel_multiplier"),
        ({"cost_travel_multiplier": math.nan}, "cost_travel_multiplier"),
        ({"min_turning_radius": -1.0}, "min_turning_radius"),
        ({"inflation_radius": 0.1}, "inscribed radius"),
    ],
)
@pytest.mark.parametrize("planner_id", ["astar", "se2", "mspp", "mspp_local", "tunnel"])
def test_bad_cost_parameters_are_refused_by_name(planner_id, params, needle):
    with pytest.raises(InvalidRequest, match=needle):
        registry.make_planner(planner_id, rectangle(0.9, 0.3), **params)


def test_direct_construction_checks_too():
    with pytest.raises(InvalidRequest, match="inscribed radius"):
        CostModel.of(0.3, 0.3, inflation_radius=0.2)
    with pytest.raises(InvalidRequest, match="cost_scaling_factor"):
        CostModel.of(0.0, 0.0, cost_scaling_factor=float("nan"))
    assert CostModel.of(0.15, 0.47).inflation_radius == 0.55  # Nav2's default
    assert CostModel.of(0.3, 0.8).inflation_radius == 0.8  # at least the circumscribed radius


@pytest.mark.parametrize(
    "param, needle",
    [
        ("inflation_radius=-1", "inflation_radius"),
        ("inflation_radius=0.05", "inscribed radius"),
        ("cost_scaling_factor=-3", "cost_scaling_factor"),
        ('cost_travel_multiplier="NaN"', "cost_travel_multiplier"),
        ("smooth=3", "smooth"),
    ],
)
def test_cli_bad_cost_parameter_is_one_line_and_exit_2(capsys, param, needle):
    code = main(
        [
            "--map",
            MEDIUM,
            "--planner",
            "astar",
            "--start",
            "1",
            "2",
            "0",
            "--goal",
            "5",
            "2",
            "0",
            "--footprint",
            "disc:0.1",
            "--param",
            param,
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and needle in err[0] and "Traceback" not in err[0], err


@pytest.mark.parametrize("planner_id", ["astar", "se2", "mspp", "tunnel"])
def test_start_or_goal_in_a_lethal_cell_is_a_clear_status(planner_id):
    occupied = np.zeros((40, 40), bool)
    occupied[20, :] = True
    grid = OccupancyGrid(occupied, 0.1)
    lethal = (1.05, 2.0 + 0.05, 0.0)  # 0.05 m from the wall's cell centres: within the 0.15 m inscribed radius
    free = (1.05, 0.55, 0.0)
    robot = rectangle(0.4, 0.3)
    start = registry.plan(planner_id, grid, lethal, free, robot, cost_travel_multiplier=1.0)
    goal = registry.plan(planner_id, grid, free, lethal, robot, cost_travel_multiplier=1.0)
    assert start.status is PlanStatus.START_OCCUPIED and "start" in start.message and "\n" not in start.message
    assert goal.status is PlanStatus.GOAL_OCCUPIED and "goal" in goal.message
