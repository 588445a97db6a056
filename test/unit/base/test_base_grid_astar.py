"""OccupancyGrid (map_server I/O, conversions, inflation) and the 2-D A*."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from maru_planner.base.astar import astar_2d, path_cost
from maru_planner.base.grid import OccupancyGrid


def brute_force_octile(occupied, start, goal):
    """Dijkstra over the same move set (reference for optimality)."""
    import heapq

    h, w = occupied.shape
    dist = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if (r, c) == goal:
            return d
        if d > dist[(r, c)]:
            continue
        for dr, dc in itertools.product((-1, 0, 1), repeat=2):
            nr, nc = r + dr, c + dc
            if (dr, dc) == (0, 0) or not (0 <= nr < h and 0 <= nc < w) or occupied[nr, nc]:
                continue
            if dr and dc and (occupied[r + dr, c] or occupied[r, c + dc]):
                continue
            nd = d + (math.sqrt(2) if dr and dc else 1.0)
            if nd < dist.get((nr, nc), math.inf):
                dist[(nr, nc)] = nd
                heapq.heappush(heap, (nd, (nr, nc)))
    return math.inf


def test_world_cell_round_trip_with_rotated_origin():
    grid = OccupancyGrid(np.zeros((20, 30), bool), resolution=0.1, origin=(1.0, -2.0, 0.3))
    for row, col in [(0, 0), (5, 7), (19, 29)]:
        x, y = grid.cell_to_world(row, col)
        assert grid.world_to_cell(x, y) == (row, col)
    c, s = math.cos(0.3), math.sin(0.3)
    assert grid.world_to_cell(1.0 + 0.05 * c - 0.15 * s, -2.0 + 0.05 * s + 0.15 * c) == (1, 0)
    assert not grid.in_bounds(*grid.world_to_cell(-5.0, 0.0))


def test_row_is_y_and_col_is_x():
    grid = OccupancyGrid(np.zeros((4, 6), bool), resolution=0.5, origin=(0.0, 0.0, 0.0))
    assert grid.cell_to_world(1, 3) == pytest.approx((1.75, 0.75))
    assert grid.world_to_cell(2.9, 1.9) == (3, 5)


def test_yaml_pgm_round_trip(tmp_path):
    occ = np.zeros((10, 12), bool)
    occ[2, 3] = occ[7, 10] = True
    unknown = np.zeros_like(occ)
    unknown[9, 0] = True
    grid = OccupancyGrid(occ, 0.05, (-1.0, 2.0, 0.0), unknown)
    grid.save_yaml(tmp_path / "m.yaml")
    back = OccupancyGrid.from_yaml(tmp_path / "m.yaml")
    assert back.shape == (10, 12) and back.resolution == 0.05 and back.origin == (-1.0, 2.0, 0.0)
    assert np.array_equal(back.unknown, unknown)
    assert np.array_equal(back.occupied, occ | unknown)
    free_unknown = OccupancyGrid.from_yaml(tmp_path / "m.yaml", unknown_is_occupied=False)
    assert np.array_equal(free_unknown.occupied, occ)
    # image row 0 is the top of the map: occupied cell (7, 10) is pixel row 10 - 1 - 7 = 2
    from PIL import Image

    pixels = np.asarray(Image.open(tmp_path / "m.pgm"))
    assert pixels[2, 10] == 0 and pixels[0, 0] == 205 and pixels[5, 5] == 254


def test_negate_and_thresholds(tmp_path):
    from PIL import Image

    pixels = np.array([[0, 100, 200, 255]], dtype=np.uint8)
    Image.fromarray(pixels).save(tmp_path / "n.pgm")
    (tmp_path / "n.yaml").write_text(
        "image: n.pgm\nresolution: 1.0\norigin: [0, 0, 0]\nnegate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.2\n"
    )
    grid = OccupancyGrid.from_yaml(tmp_path / "n.yaml", unknown_is_occupied=False)
    # negate: p = v / 255 -> 0 free, 0.39 unknown, 0.78 occupied, 1.0 occupied
    assert grid.occupied[0].tolist() == [False, False, True, True]
    assert grid.unknown[0].tolist() == [False, True, False, False]


def test_from_values_rejects_bad_data():
    with pytest.raises(ValueError, match="empty"):
        OccupancyGrid.from_values([], 0, 0, 0.1)
    with pytest.raises(ValueError, match="12 values"):
        OccupancyGrid.from_values([0] * 12, 5, 3, 0.1)
    grid = OccupancyGrid.from_values([0, 100, -1, 50, 70, 0], 3, 2, 0.1)
    assert grid.occupied.tolist() == [[False, True, True], [False, True, False]]


def test_inflation_is_exact_disc():
    occ = np.zeros((41, 41), bool)
    occ[20, 20] = True
    grid = OccupancyGrid(occ, resolution=0.1)
    grown = grid.inflate(0.5)
    rows, cols = np.mgrid[0:41, 0:41]
    expected = np.hypot(rows - 20, cols - 20) * 0.1 <= 0.5 + 1e-12
    assert np.array_equal(grown.occupied, expected)
    assert grown.occupied.sum() == 81  # lattice points in a disc of radius 5
    assert np.array_equal(grid.inflate(0.0).occupied, occ)


def test_astar_straight_diagonal_and_no_corner_cutting():
    grid = OccupancyGrid.from_ascii(
        [
            "....",
            ".#..",
            "....",
        ]
    )
    occ = grid.occupied  # row 0 is the bottom text line
    path, cost, _ = astar_2d(occ, (0, 0), (2, 2))
    # (1,1) is blocked and no diagonal may cut past it: right 2, up 2
    assert cost == pytest.approx(brute_force_octile(occ, (0, 0), (2, 2)))
    assert cost == pytest.approx(4.0)
    assert astar_2d(occ, (0, 0), (0, 3)).cost == pytest.approx(3.0)
    assert astar_2d(np.zeros((3, 3), bool), (0, 0), (2, 2)).cost == pytest.approx(2 * math.sqrt(2))
    for (r0, c0), (r1, c1) in zip(path[:-1], path[1:], strict=False):
        if r0 != r1 and c0 != c1:
            assert not occ[r1, c0] and not occ[r0, c1]
    assert path_cost(path) == pytest.approx(cost)


def test_astar_squeeze_between_diagonal_obstacles_is_refused():
    occ = np.array([[False, True], [True, False]])
    path, cost, _ = astar_2d(occ, (0, 0), (1, 1))
    assert len(path) == 0 and math.isinf(cost)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("variant", ["jps", "astar"])
def test_astar_is_optimal_on_random_maps(seed, variant):
    kwargs = {"method": variant}
    rng = np.random.default_rng(seed)
    occ = rng.random((25, 30)) < (0.1 + 0.06 * seed)
    free = np.argwhere(~occ)
    for _ in range(5):
        s, g = (tuple(int(v) for v in free[i]) for i in rng.choice(len(free), 2, replace=False))
        path, cost, expansions = astar_2d(occ, s, g, **kwargs)
        expected = brute_force_octile(occ, s, g)
        if math.isinf(expected):
            assert len(path) == 0 and math.isinf(cost)
            continue
        assert cost == pytest.approx(expected, abs=1e-9)
        assert tuple(path[0]) == s and tuple(path[-1]) == g
        assert not occ[path[:, 0], path[:, 1]].any()
        assert np.abs(np.diff(path, axis=0)).max() <= 1
        assert path_cost(path) == pytest.approx(cost, abs=1e-9)
        assert expansions >= 1 if variant == "jps" else expansions >= len(path)


def test_astar_rejects_cells_outside_the_map():
    with pytest.raises(ValueError, match="goal cell"):
        astar_2d(np.zeros((3, 3), bool), (0, 0), (3, 0))


def test_astar_occupied_start_gives_no_path():
    occ = np.zeros((3, 3), bool)
    occ[0, 0] = True
    path, cost, _ = astar_2d(occ, (0, 0), (2, 2))
    assert len(path) == 0 and math.isinf(cost)


def test_kernels_run_without_the_jit():
    """The same kernels interpreted (NUMBA_DISABLE_JIT=1) give the same answers: the fallback stays correct."""
    import os
    import subprocess
    import sys

    code = """
import math, numpy as np
from maru_planner.base.astar import astar_2d
from maru_planner.base.footprint import rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.se2 import SE2AStarPlanner
rng = np.random.default_rng(1)
occ = rng.random((15, 18)) < 0.2
occ[0, 0] = occ[14, 17] = False
a, j = (astar_2d(occ, (0, 0), (14, 17), **kw).cost for kw in ({"method": "astar"}, {}))
assert (math.isinf(a) and math.isinf(j)) or abs(a - j) < 1e-9, (a, j)
grid = OccupancyGrid(np.zeros((12, 12), bool), 0.1)
r = SE2AStarPlanner(rectangle(0.4, 0.2), headings=8).plan(grid, (0.25, 0.25, 0.0), (0.95, 0.85, 1.5708))
assert r.success and len(r.path) > 2, r.message
print("ok")
"""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 0 and "ok" in out.stdout, out.stdout + out.stderr
