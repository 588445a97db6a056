"""The BARN world builder: cylinders at the grid's cells plus the containment walls, in the challenge's frame."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.errors import InvalidMap, InvalidRequest
from maru_planner.physics.barn_world import (
    OBSTACLE_GROUP,
    barn_dir,
    check_grid,
    cylinder_centres,
    full_grid,
    load_grid,
    world_grid,
)
from maru_planner.physics.base_sim import BaseSim

WALL_CYLINDERS = 30 + 2 * 33  # back wall + two side walls
needs_data = pytest.mark.skipif(not (barn_dir() / "grid_files").is_dir(), reason="BARN data not present")


def test_cylinder_count_equals_the_grids_plus_walls():
    rng = np.random.default_rng(3)
    grid = (rng.random((30, 30)) < 0.2).astype(np.uint8)
    sim = BaseSim(grid)
    cylinders = int(np.sum(sim.model.geom_group == OBSTACLE_GROUP))
    assert cylinders == int(grid.sum()) + WALL_CYLINDERS
    assert len(cylinder_centres(grid)) == cylinders


def test_field_cell_is_at_the_challenges_coordinates():
    grid = np.zeros((30, 30), np.uint8)
    grid[7, 11] = 1
    centres = cylinder_centres(grid)
    assert np.any(np.all(np.isclose(centres, (-4.425 + 0.15 * 7, 5.175 + 0.15 * 11)), axis=1))


@needs_data
def test_full_grid_matches_the_dataset():
    for index in (0, 150):
        expected = np.load(barn_dir() / "full_grid_files" / f"full_grid_{index}.npy")
        assert np.array_equal(full_grid(world_grid(index)), expected)


@pytest.mark.parametrize(
    "bad, words",
    [
        (np.zeros((30, 31), np.uint8), "shape"),
        (np.zeros((30, 30), np.float64), "dtype"),
        (np.full((30, 30), 2, np.uint8), "only 0 and 1"),
    ],
)
def test_bad_grids_are_refused(bad, words):
    with pytest.raises(InvalidMap, match=words):
        check_grid(bad)


def test_unreadable_grid_file_is_one_line(tmp_path):
    path = tmp_path / "grid.npy"
    path.write_text("not numpy")
    with pytest.raises(InvalidRequest, match="cannot read grid file"):
        load_grid(path)
    with pytest.raises(InvalidRequest, match="0..299"):
        world_grid(300)
