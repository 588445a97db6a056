"""Maps for the paper-003 benchmark: the paper's 250 × 250 house and generated maps of any size.

``python bench/paper003_maps.py`` rewrites ``config/maps/house_250.yaml/.pgm``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
HOUSE_YAML = ROOT / "config" / "maps" / "house_250.yaml"
# The paper's query: A (blue) in a bedroom, B (green) in the kitchen; metres in the map frame.
HOUSE_START = (2.5, 21.0, 0.0)
HOUSE_GOAL = (22.0, 3.0, 0.0)
HOUSE_RADIUS = 0.25


def _box(occ, x0, y0, x1, y1, res=0.1):
    """Mark the metres box [x0, x1] × [y0, y1] (row = y)."""
    occ[int(round(y0 / res)) : int(round(y1 / res)), int(round(x0 / res)) : int(round(x1 / res))] = True


def house_occupancy() -> np.ndarray:
    """250 × 250 cells of 10 cm: two bedrooms (north), living room and kitchen (south), furniture."""
    occ = np.zeros((250, 250), dtype=bool)
    wall = 0.2
    _box(occ, 0, 0, 25, wall)
    _box(occ, 0, 25 - wall, 25, 25)
    _box(occ, 0, 0, wall, 25)
    _box(occ, 25 - wall, 0, 25, 25)
    # wall between the bedrooms (north) and the living room / kitchen (south), with two doors
    _box(occ, 0, 12.0, 5.0, 12.2)
    _box(occ, 6.2, 12.0, 18.0, 12.2)
    _box(occ, 19.2, 12.0, 25, 12.2)
    # wall between the two bedrooms, with a closet corner (the paper's wall C)
    _box(occ, 12.4, 12.0, 12.6, 25)
    _box(occ, 9.5, 16.0, 12.4, 16.2)
    # living room | kitchen wall with one door; a partition stub below it (the paper's wall E)
    _box(occ, 16.0, 0, 16.2, 8.0)
    _box(occ, 16.0, 9.2, 16.2, 12.0)
    _box(occ, 8.0, 7.0, 8.2, 10.5)
    # furniture: beds, wardrobe, desk, sofa, TV stand, dining table, counters
    _box(occ, 0.2, 17.0, 2.2, 23.0)
    _box(occ, 4.0, 23.8, 8.0, 24.8)
    _box(occ, 21.0, 18.0, 24.8, 20.0)
    _box(occ, 14.0, 23.5, 16.5, 24.8)
    _box(occ, 3.0, 3.0, 7.0, 4.0)
    _box(occ, 2.0, 0.2, 6.0, 0.7)
    _box(occ, 10.0, 3.0, 12.0, 5.0)
    _box(occ, 19.0, 4.0, 21.0, 6.0)
    _box(occ, 16.2, 10.8, 24.8, 11.8)
    _box(occ, 24.0, 0.2, 24.8, 9.0)
    return occ


def rooms_map(n: int, seed: int, room: int = 25, door: int = 10) -> np.ndarray:
    """An n × n floor of square rooms (walls 1 cell, one door per wall side) plus random furniture."""
    rng = np.random.default_rng(seed)
    occ = np.zeros((n, n), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    for k in range(room, n - 1, room):
        occ[k, :] = True
        occ[:, k] = True
    for k in range(room, n - 1, room):
        for start in range(0, n, room):
            for along_rows in (True, False):
                if rng.random() < 0.1:
                    continue  # some walls have no door
                lo = start + 2 + int(rng.integers(0, max(1, room - door - 3)))
                hi = min(lo + door, n - 1)
                if along_rows:
                    occ[k, lo:hi] = False
                else:
                    occ[lo:hi, k] = False
    for _ in range(n * n // (room * room) * 2):
        r, c = rng.integers(1, n - 1, 2)
        h, w = rng.integers(1, max(2, room // 3), 2)
        occ[r : r + h, c : c + w] = True
    return occ


def random_boxes_map(n: int, seed: int, fill: float = 0.2) -> np.ndarray:
    """n × n cells with random rectangles until about ``fill`` of the cells are occupied."""
    rng = np.random.default_rng(seed)
    occ = np.zeros((n, n), dtype=bool)
    side = max(2, n // 25)
    while occ.mean() < fill:
        r, c = rng.integers(0, n, 2)
        h, w = rng.integers(1, side + 1, 2)
        occ[r : r + h, c : c + w] = True
    return occ


def far_free_pair(occ: np.ndarray) -> tuple[tuple, tuple]:
    """Start near the lower-left corner, goal near the upper-right one, in the largest free 4-connected region."""
    from scipy import ndimage

    labels, count = ndimage.label(~occ)
    if count == 0:
        raise ValueError("the map has no free cell")
    largest = 1 + int(np.argmax(np.bincount(labels.ravel())[1:]))
    free = np.argwhere(labels == largest)
    n0, n1 = occ.shape
    start = free[np.argmin(free[:, 0] + free[:, 1])]
    goal = free[np.argmin((n0 - 1 - free[:, 0]) + (n1 - 1 - free[:, 1]))]
    return tuple(int(v) for v in start), tuple(int(v) for v in goal)


def write_house(path: Path = HOUSE_YAML) -> Path:
    sys.path.insert(0, str(ROOT))
    from maru_planner.base.grid import OccupancyGrid

    grid = OccupancyGrid(house_occupancy(), 0.1, (0.0, 0.0, 0.0))
    return grid.save_yaml(path)


if __name__ == "__main__":
    print(write_house())
