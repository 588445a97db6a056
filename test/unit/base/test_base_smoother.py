"""The smoother: never nearer to an obstacle than the planned path, re-checked on the planner's grid, SE(2) turns
and headings kept, the turning-radius limit honoured, the deadline respected."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.base import registry
from maru_planner.base.budget import Deadline
from maru_planner.base.clearance import distance_transform, path_clearance, segment_distance, to_cell_units
from maru_planner.base.footprint import disc, footprint_collides, rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.smoother import (
    SmootherParams,
    Stretch,
    segment_free,
    smooth_stretch,
    stretches_at_headings,
    turn_rates,
)
from maru_planner.paths import config_path

HOUSE = OccupancyGrid.from_yaml(config_path("maps", "house_250.yaml"))


def random_room(seed: int) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    occupied = np.zeros((60, 80), bool)
    occupied[0, :] = occupied[-1, :] = occupied[:, 0] = occupied[:, -1] = True
    for _ in range(14):
        r, c = rng.integers(3, 57), rng.integers(3, 77)
        occupied[r : r + rng.integers(1, 6), c : c + rng.integers(1, 6)] = True
    return OccupancyGrid(occupied, 0.1)


def segment_minima(grid: OccupancyGrid, xy: np.ndarray) -> np.ndarray:
    cells = to_cell_units(grid, xy)
    occ = np.ascontiguousarray(grid.occupied)
    return (
        np.array([segment_distance(occ, cells[j], cells[j + 1], 1e9) for j in range(len(cells) - 1)]) * grid.resolution
    )


def assert_never_nearer(grid, before, after, cap):
    """Each smoothed segment keeps the clearance of the planned segments around it (up to the cap)."""
    old, new = np.minimum(segment_minima(grid, before), cap), np.minimum(segment_minima(grid, after), cap)
    window = old.copy()
    window[1:] = np.minimum(window[1:], old[:-1])
    window[:-1] = np.minimum(window[:-1], old[1:])
    assert np.all(new >= window - 1e-9)
    assert path_clearance(grid, after).min_m >= min(path_clearance(grid, before).min_m, cap) - 1e-9


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("planner_id", ["astar", "mspp", "tunnel"])
def test_smoothing_never_brings_the_path_nearer_and_is_rechecked_on_the_grid(planner_id, seed):
    grid = random_room(seed)
    rng = np.random.default_rng(100 + seed)
    grown = grid.inflate(0.25).occupied
    free = np.argwhere(~grown)
    s, g = (grid.cell_to_world(*free[i]) for i in rng.choice(len(free), 2, replace=False))
    robot = disc(0.25)
    plain = registry.plan(planner_id, grid, (*s, 0.0), (*g, 0.0), robot)
    smooth = registry.plan(planner_id, grid, (*s, 0.0), (*g, 0.0), robot, smooth=True)
    assert plain.success == smooth.success
    if not plain.success:
        return
    assert smooth.stats.smoothing is None if len(plain.path) < 3 else smooth.stats.smoothing["accepted"]
    assert np.allclose(smooth.path[[0, -1], :2], plain.path[[0, -1], :2])
    assert smooth.path_length() <= plain.path_length() + 1e-9
    assert_never_nearer(grid, plain.path[:, :2], smooth.path[:, :2], cap=0.55)
    before, after = to_cell_units(grid, plain.path[:, :2]), to_cell_units(grid, smooth.path[:, :2])
    moved = np.any(np.abs(after - before) > 1e-9, axis=1)
    for j in range(len(after) - 1):  # every changed segment touches only cells free on the grown map
        assert not (moved[j] or moved[j + 1]) or segment_free(grown, 0, 0, after[j], after[j + 1])


def test_smoothing_shortens_the_house_path_and_keeps_its_distance():
    start, goal = (2.5, 21.0, 0.0), (22.0, 3.0, 0.0)
    plain = registry.plan("astar", HOUSE, start, goal, disc(0.3))
    smooth = registry.plan("astar", HOUSE, start, goal, disc(0.3), smooth=True)
    assert smooth.stats.smoothing["accepted"] and smooth.stats.smoothing["moved"] > 50
    assert smooth.path_length() < plain.path_length() - 0.3
    assert_never_nearer(HOUSE, plain.path[:, :2], smooth.path[:, :2], cap=0.55)


def test_se2_smoothing_keeps_headings_and_turns_in_place():
    grid, robot = random_room(3), rectangle(0.5, 0.2)
    start, goal = (1.0, 1.0, 0.0), (7.0, 5.0, math.pi / 2)
    plain = registry.plan("se2", grid, start, goal, robot, headings=16)
    smooth = registry.plan("se2", grid, start, goal, robot, headings=16, smooth=True)
    assert plain.success and smooth.success and smooth.stats.smoothing["accepted"]
    assert np.array_equal(smooth.path[:, 2], plain.path[:, 2])  # the same heading at every pose
    turns = [i for i in range(1, len(plain.path)) if plain.path[i, 2] != plain.path[i - 1, 2]]
    for i in turns:  # the turns in place are where the planner put them
        assert np.allclose(smooth.path[i, :2], plain.path[i, :2]) and np.allclose(
            smooth.path[i - 1, :2], plain.path[i - 1, :2]
        )
    for x, y, theta in smooth.path:  # every pose of the smoothed path is free at its heading
        assert not footprint_collides(grid.occupied, robot, grid.resolution, *grid.world_to_cell(x, y), theta)
    assert_never_nearer(grid, plain.path[:, :2], smooth.path[:, :2], cap=0.55)


def test_stretches_split_at_turns_in_place():
    path = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0, 1], [2, 1, 1], [2, 2, 1], [2, 2, 2]], dtype=float)
    assert stretches_at_headings(path) == [(0, 2), (3, 5)]


def _zigzag_stretch():
    grid = OccupancyGrid(np.pad(np.zeros((30, 60), bool), 1, constant_values=True), 0.1)
    rows = 15 + np.array([0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0], float)
    points = np.column_stack([rows + 0.5, np.arange(13) * 1.0 + 10.5])
    dist = distance_transform(grid.occupied)
    return grid, points, dist


def test_the_turning_radius_limit_is_honoured():
    grid, points, dist = _zigzag_stretch()
    stretch = Stretch(0, len(points) - 1, grid.occupied)
    radius = 0.6
    limited = smooth_stretch(points, stretch, grid.occupied, dist, 5.5, SmootherParams(min_turning_radius=radius), 0.1)
    free = smooth_stretch(points, stretch, grid.occupied, dist, 5.5, SmootherParams(), 0.1)
    assert limited.accepted and free.accepted
    limit = 0.1 / radius  # per cell
    before, after = turn_rates(points), turn_rates(limited.points)
    assert np.all(after <= np.maximum(limit, before) + 1e-9)
    assert np.max(turn_rates(free.points)) < np.max(before)  # smoothing alone also lowers the sharpest turn


def test_an_expired_deadline_keeps_the_planned_path():
    grid, points, dist = _zigzag_stretch()
    deadline = Deadline(1.0)
    deadline.terminate()
    out = smooth_stretch(
        points, Stretch(0, len(points) - 1, grid.occupied), grid.occupied, dist, 5.5, SmootherParams(), 0.1, deadline
    )
    assert not out.accepted and np.array_equal(out.points, points)


def test_a_path_along_a_wall_is_not_pulled_towards_it():
    occupied = np.zeros((20, 60), bool)
    occupied[5, :] = True  # a wall below the path
    grid = OccupancyGrid(occupied, 0.1)
    # a staircase above the wall: its lower steps are as near as the wall lets it be
    rows = 8 + np.array([0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0], float)
    points = np.column_stack([rows + 0.5, np.arange(13) * 1.0 + 20.5])
    dist = distance_transform(grid.occupied)
    out = smooth_stretch(points, Stretch(0, len(points) - 1, grid.occupied), occupied, dist, 5.5, SmootherParams(), 0.1)
    assert out.accepted
    assert out.points[:, 0].min() >= points[:, 0].min() - 1e-9  # no vertex moved nearer the wall
