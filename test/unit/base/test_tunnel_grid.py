"""Tunnel planner on OccupancyGrid maps: the paper's house, agreement with A*, safety on the grown map."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from maru_planner.base.astar import GridAStarPlanner, astar_2d
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import PlanStatus as res
from maru_planner.base.tunnel import TunnelGridPlanner
from maru_planner.errors import InvalidRequest
from maru_planner.paths import config_path

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "bench"))
from paper003_maps import HOUSE_GOAL, HOUSE_START, far_free_pair, random_boxes_map, rooms_map  # noqa: E402


def path_is_free(grid: OccupancyGrid, occupied: np.ndarray, path: np.ndarray) -> bool:
    """Every point of every segment, sampled each 1/20 cell, lies in a free cell of ``occupied``."""
    for a, b in zip(path[:-1, :2], path[1:, :2]):
        n = int(20 * np.linalg.norm(b - a) / grid.resolution) + 2
        for t in np.linspace(0.0, 1.0, n):
            row, col = grid.world_to_cell(*(a + t * (b - a)))
            if occupied[row, col]:
                return False
    return True


@pytest.fixture(scope="module")
def house():
    return OccupancyGrid.from_yaml(config_path("maps", "house_250.yaml"))


def test_house_map_is_the_papers_size(house):
    assert house.shape == (250, 250) and house.resolution == pytest.approx(0.1)


def test_house_query_solved_on_the_grown_map(house):
    plan = TunnelGridPlanner(robot_radius=0.25).plan(house, HOUSE_START, HOUSE_GOAL)
    assert plan.status == res.SOLVED, plan.message
    np.testing.assert_allclose(plan.path[0], HOUSE_START)
    np.testing.assert_allclose(plan.path[-1], HOUSE_GOAL)
    grown = house.inflate(0.25).occupied
    assert path_is_free(house, grown, plan.path)
    optimal = GridAStarPlanner(robot_radius=0.25, cost_travel_multiplier=0.0).plan(house, HOUSE_START, HOUSE_GOAL)
    assert plan.path_length() <= 1.3 * optimal.path_length()
    plain = astar_2d(grown, house.world_to_cell(*HOUSE_START[:2]), house.world_to_cell(*HOUSE_GOAL[:2]), method="astar")
    assert plan.stats.expansions < plain.expansions  # the paper's point: far fewer cells looked at
    assert {"attempts", "raw_cells", "waypoints", "grown"} <= set(plan.layers)


def test_footprint_gives_the_radius(house):
    square = np.array([[0.2, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.2, -0.2]])
    assert TunnelGridPlanner(square).robot_radius == pytest.approx(np.hypot(0.2, 0.2))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("kind", ["rooms", "boxes"])
def test_agrees_with_astar_on_generated_maps(kind, seed):
    occ = rooms_map(90, seed, room=30) if kind == "rooms" else random_boxes_map(90, seed, fill=0.1)
    grid = OccupancyGrid(occ, 0.1, (0.0, 0.0, 0.0))
    grown = grid.inflate(0.15).occupied
    s, g = far_free_pair(grown)
    start, goal = (*grid.cell_to_world(*s), 0.0), (*grid.cell_to_world(*g), 0.0)
    plan = TunnelGridPlanner(robot_radius=0.15).plan(grid, start, goal)
    astar = astar_2d(grown, s, g)
    assert plan.success == (len(astar.path) > 0), plan.message
    if plan.success:
        assert path_is_free(grid, grown, plan.path)


def test_bad_requests(house):
    planner = TunnelGridPlanner(robot_radius=0.25)
    assert planner.plan(house, (-5.0, 1.0, 0.0), HOUSE_GOAL).status == res.START_OUTSIDE_MAP
    assert planner.plan(house, HOUSE_START, (0.05, 0.05, 0.0)).status == res.GOAL_OCCUPIED
    assert planner.plan(house, (float("nan"), 1.0, 0.0), HOUSE_GOAL).status == res.INVALID_REQUEST
    with pytest.raises(InvalidRequest):
        TunnelGridPlanner(robot_radius=-1.0)


def test_time_limit_reports_timed_out():
    occ = rooms_map(400, 3, room=25)
    s, g = far_free_pair(occ)
    grid = OccupancyGrid(occ, 0.1)
    start, goal = (*grid.cell_to_world(*s), 0.0), (*grid.cell_to_world(*g), 0.0)
    planner = TunnelGridPlanner(robot_radius=0.0)
    timed_out = planner.plan(grid, start, goal, time_limit=1e-4)
    assert timed_out.status == res.TIMED_OUT and len(timed_out.path) == 0 and "timed out" in timed_out.message
    assert planner.plan(grid, start, goal, time_limit=60.0).status == res.SOLVED


def test_parameters_are_the_papers_and_nothing_else():
    planner = TunnelGridPlanner(None, big_cell_size=4)
    assert planner.planner.params.big_cell_size == 4 and planner.robot_radius == 0.25
    with pytest.raises(InvalidRequest, match="headings"):  # nothing the tunnel planner would ignore
        TunnelGridPlanner(None, headings=32)
