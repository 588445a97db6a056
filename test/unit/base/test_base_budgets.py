"""Hard budgets of base planning: every long loop checks the deadline, what cannot fit is refused up front."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from maru_planner.base import registry
from maru_planner.base.astar import astar_2d
from maru_planner.base.biped.wall import cost_to_go
from maru_planner.base.budget import MAX_MAP_CELLS, Deadline
from maru_planner.base.footprint import heading_offsets, rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import PlanStatus
from maru_planner.base.scenes import table1
from maru_planner.base.se2 import cspace_layers, search_layers
from maru_planner.errors import PlanningCancelled, PlanningTimedOut, TooLarge

HUGE = rectangle(100.0, 100.0)


def random_grid(n: int, fill: float, seed: int = 0, resolution: float = 0.05) -> OccupancyGrid:
    return OccupancyGrid(np.random.default_rng(seed).random((n, n)) < fill, resolution)


@pytest.mark.parametrize("planner_id", registry.planner_ids())
def test_a_100_m_footprint_is_answered_not_computed_for_a_minute(planner_id):
    result = registry.plan(planner_id, table1("easy"), (1.0, 2.0, 0.0), (5.0, 2.0, 0.0), HUGE, time_limit=5.0)
    assert result.status in (PlanStatus.START_OCCUPIED, PlanStatus.INVALID_REQUEST), result.message
    assert "start" in result.message or "gait rectangle" in result.message


def test_a_100_m_footprint_on_a_big_map_is_refused_with_an_estimate():
    result = registry.plan(
        "se2", random_grid(2000, 0.001), (10.0, 10.0, 0.0), (90.0, 90.0, 0.0), HUGE, time_limit=5.0, headings=64
    )
    assert result.status == PlanStatus.INVALID_REQUEST
    assert "rasterising the footprint" in result.message and "GB, over the 2 GB limit" in result.message


def test_se2_on_4000_square_is_refused_before_allocating():
    grid = OccupancyGrid(np.zeros((4000, 4000), bool), 0.05)
    result = registry.plan("se2", grid, (1.0, 1.0, 0.0), (190.0, 190.0, 1.0), rectangle(0.9, 0.3), time_limit=5.0)
    assert result.status == PlanStatus.INVALID_REQUEST
    assert "SE(2) A* over 32 headings x 4000 x 4000 cells needs about 9.1 GB" in result.message


def test_rasterising_checks_the_deadline():
    with pytest.raises(PlanningTimedOut, match="rasterising the footprint"):
        heading_offsets(rectangle(20.0, 20.0), 0.05, 32, (1000, 1000), Deadline(1e-4))


def test_cspace_stamping_checks_the_deadline():
    grid = random_grid(500, 0.3)
    offsets = heading_offsets(rectangle(2.0, 2.0), grid.resolution, 32, grid.shape)
    with pytest.raises(PlanningTimedOut, match="footprint C-space"):
        cspace_layers(grid.occupied, None, grid.resolution, 32, offsets, Deadline(1e-3))


def test_se2_search_checks_the_deadline():
    layers = np.zeros((32, 600, 600), bool)
    with pytest.raises(PlanningTimedOut, match="SE\\(2\\) A\\*"):
        search_layers(layers, [(0, 0, 0)], (599, 599), 16, 3.0, deadline=Deadline(1e-3))


def test_2d_astar_checks_the_deadline():
    occupied = np.zeros((1500, 1500), bool)
    occupied[1400:1403, 1400:1403] = True
    occupied[1401, 1401] = False  # the goal is walled in: A* must look at every other cell
    with pytest.raises(PlanningTimedOut, match="2-D A\\*"):
        astar_2d(occupied, (0, 0), (1401, 1401), method="astar", deadline=Deadline(1e-4))


def test_a_terminated_deadline_stops_a_kernel_as_a_cancel():
    deadline = Deadline(60.0)
    assert not deadline.cancelled and deadline.remaining() > 0
    deadline.terminate()
    assert deadline.cancelled and deadline.expired()
    occupied = np.zeros((300, 300), bool)
    occupied[0:3, 297:300] = True
    occupied[1, 298] = False  # the goal is walled in: the kernel reaches its clock check
    with pytest.raises(PlanningCancelled, match="2-D A\\* .* cancelled"):
        astar_2d(occupied, (299, 0), (1, 298), method="astar", deadline=deadline)


def test_reserve_raises_for_the_deadline_unless_the_time_is_left():
    deadline = Deadline(60.0)
    deadline.reserve(1.0, "a short step")
    with pytest.raises(PlanningTimedOut, match="a long step \\(needs about 120.00 s, .* left\\) timed out"):
        deadline.reserve(120.0, "a long step")
    deadline.terminate()
    with pytest.raises(PlanningCancelled, match="a short step .* cancelled"):
        deadline.reserve(1.0, "a short step")


def test_map_inflation_checks_the_deadline():
    grid = random_grid(3000, 0.05)
    with pytest.raises(PlanningTimedOut, match="inflating the map"):
        grid.inflate(0.5, Deadline(1e-4))


def test_strip_inflation_is_exact():
    grid = random_grid(700, 0.01, seed=3, resolution=0.1)
    expected = ndimage.distance_transform_edt(~grid.occupied) * 0.1 <= 1.3 + 1e-10
    assert np.array_equal(grid.inflate(1.3).occupied, expected)


def test_whole_plans_time_out_in_every_planner():
    grid = random_grid(1200, 0.02, seed=5)
    for planner_id in registry.planner_ids():
        result = registry.plan(
            planner_id, grid, (2.0, 2.0, 0.0), (58.0, 58.0, 0.0), rectangle(0.3, 0.2), time_limit=1e-3
        )
        assert result.status in (PlanStatus.TIMED_OUT, PlanStatus.START_OCCUPIED, PlanStatus.GOAL_OCCUPIED), (
            planner_id,
            result.status,
            result.message,
        )


def test_map_size_limit():
    side = int(MAX_MAP_CELLS**0.5) + 1
    with pytest.raises(TooLarge, match="over the limit"):
        OccupancyGrid(np.zeros((side, side), bool), 0.05)


def test_biped_cost_to_go_checks_the_deadline():
    with pytest.raises(PlanningTimedOut, match="cost-to-go wavefront over 2000 x 2000 cells"):
        cost_to_go(np.ones((2000, 2000), bool), (0, 0), deadline=Deadline(1e-3))
    small = np.ones((5, 5), bool)
    small[1:4, 2] = False
    field = cost_to_go(small, (2, 0))
    assert field[2, 0] == 0 and field[2, 1] == 1 and np.isinf(field[2, 2])
    assert field[2, 4] == pytest.approx(4 + 2 * np.sqrt(2))  # over the wall's end, no corner cutting
