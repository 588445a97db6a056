"""Paper 002's scenes, rebuilt: Table I (60 x 40 grid) and the house (living room, sofa, partition, bed).

The paper's figures are not in our copy of the paper (text only), so the
scenes follow its text: "the same robot and environment, varying the width of
the free space on the main passage" (Table I), and a living room whose narrow
gap between sofa and partition forces the full search (house). Choices:

- Table I grid: 60 x 40 cells of 0.1 m (6 m x 4 m), walls on the border, a
  wall across the room at x = 3 m holding the main passage, three boxes.
- robot: a 0.9 m x 0.3 m rectangle centred on its reference point
  (R_min = 0.15 m, R_max = 0.474 m), 32 headings;
- easy: a 1.2 m passage (wider than 2 R_max: BAA solves it);
  medium: a 0.6 m passage (the robot must face it: full search);
  hard: two 0.5 m passages in two walls 1.1 m apart, offset (turn between);
  impossible: a 0.2 m passage (narrower than 2 R_min: ECA disproves it).
- house: 10 m x 8 m at 0.1 m; robot 0.8 m x 0.45 m; the bedroom's 1.0 m
  doorway in the partition is reached only through the 0.6 m gap between the
  sofa and the partition (the robot drives along the gap, then turns into
  the doorway); the goal is beside the bed.

``build_all()`` returns {name: (grid, problem)}; ``write_maps(dir)`` writes
``<name>.yaml/.pgm`` and ``problems.yaml`` (start, goal, footprint per map).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from maru_planner.base.footprint import rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.paths import config_path

TABLE1_SIZE = (40, 60)  # rows (y), cols (x)
TABLE1_RESOLUTION = 0.1
TABLE1_ROBOT = rectangle(0.9, 0.3)
HOUSE_ROBOT = rectangle(0.8, 0.45)


def _grid_with_boxes(shape, resolution, boxes) -> OccupancyGrid:
    """Border walls plus axis-aligned boxes (x0, y0, x1, y1) in metres (cells whose centres fall inside)."""
    occ = np.zeros(shape, dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    ys = (np.arange(shape[0]) + 0.5) * resolution
    xs = (np.arange(shape[1]) + 0.5) * resolution
    for x0, y0, x1, y1 in boxes:
        rows = (ys >= y0) & (ys <= y1)
        cols = (xs >= x0) & (xs <= x1)
        occ[np.ix_(rows, cols)] = True
    return OccupancyGrid(occ, resolution, (0.0, 0.0, 0.0))


def _wall_with_gap(x0, x1, gap_y0, gap_y1, height=4.0):
    return [(x0, 0.0, x1, gap_y0), (x0, gap_y1, x1, height)]


TABLE1_BOXES = [(0.8, 0.6, 1.4, 1.1), (1.2, 2.8, 1.8, 3.3), (4.4, 0.5, 5.0, 1.0)]
TABLE1_START = (1.0, 2.0, 0.0)
TABLE1_GOAL = (5.0, 2.0, 0.0)


def table1(difficulty: str) -> OccupancyGrid:
    """Table I map for 'easy', 'medium', 'hard' or 'impossible'."""
    wall = (2.9, 3.1)
    if difficulty == "easy":
        boxes = _wall_with_gap(*wall, 1.4, 2.6)
    elif difficulty == "medium":
        boxes = _wall_with_gap(*wall, 1.7, 2.3)
    elif difficulty == "impossible":
        boxes = _wall_with_gap(*wall, 1.9, 2.1)
    elif difficulty == "hard":
        boxes = _wall_with_gap(2.5, 2.7, 0.6, 1.1) + _wall_with_gap(3.8, 4.0, 2.9, 3.4)
    else:
        raise ValueError(f"unknown Table I difficulty {difficulty!r}")
    return _grid_with_boxes(TABLE1_SIZE, TABLE1_RESOLUTION, boxes + TABLE1_BOXES)


HOUSE_BOXES = [
    (6.0, 0.0, 6.15, 4.3),  # partition between living room and bedroom ...
    (6.0, 5.3, 6.15, 8.0),  # ... with a 1.0 m doorway at y = 4.3 .. 5.3
    (4.5, 3.3, 5.4, 6.3),  # sofa (0.9 m x 3 m) backing the doorway: a 0.6 m gap to the partition
    (1.0, 6.0, 2.5, 7.0),  # TV stand / cabinet
    (0.8, 1.0, 2.2, 2.0),  # dining table
    (7.4, 0.6, 9.4, 2.6),  # bed (2 m x 2 m)
    (9.0, 3.6, 9.9, 4.6),  # wardrobe
    (7.0, 6.8, 8.0, 7.9),  # desk
]
HOUSE_START = (2.0, 4.5, 0.0)
HOUSE_GOAL = (8.4, 3.1, 0.0)


def house() -> OccupancyGrid:
    return _grid_with_boxes((80, 100), 0.1, HOUSE_BOXES)


def problems() -> dict:
    """Each scene's start, goal, footprint and paper reference."""
    t1 = {"start": list(TABLE1_START), "goal": list(TABLE1_GOAL), "footprint": TABLE1_ROBOT.tolist()}
    return {
        "easy": {**t1, "paper": {"mspp_s": 0.6, "mspp_checks": 6657, "by": "BAA", "full_s": 445, "full_checks": 25865}},
        "medium": {
            **t1,
            "paper": {"mspp_s": 254.3, "mspp_checks": 40318, "by": "full A*", "full_s": 253, "full_checks": 24646},
        },
        "hard": {
            **t1,
            "paper": {"mspp_s": 192.3, "mspp_checks": 42782, "by": "full A*", "full_s": 191, "full_checks": 27732},
        },
        "impossible": {
            **t1,
            "paper": {"mspp_s": 0.7, "mspp_checks": 7134, "by": "ECA", "full_s": 133, "full_checks": 20824},
        },
        "house": {
            "start": list(HOUSE_START),
            "goal": list(HOUSE_GOAL),
            "footprint": HOUSE_ROBOT.tolist(),
            "paper": {"full_s": 55, "local_s": 10},
        },
    }


def build_all() -> dict:
    grids = {name: table1(name) for name in ("easy", "medium", "hard", "impossible")}
    grids["house"] = house()
    probs = problems()
    return {name: (grid, probs[name]) for name, grid in grids.items()}


def write_maps(directory) -> list[Path]:
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, (grid, _) in build_all().items():
        written.append(grid.save_yaml(directory / f"paper002_{name}.yaml"))

    class NoAliases(yaml.SafeDumper):
        def ignore_aliases(self, data):
            return True

    with open(directory / "paper002_problems.yaml", "w") as f:
        yaml.dump(
            {f"paper002_{k}": v for k, v in problems().items()},
            f,
            Dumper=NoAliases,
            sort_keys=False,
            default_flow_style=None,
        )
    return written


if __name__ == "__main__":  # regenerate config/maps/
    for p in write_maps(config_path("maps")):
        print(p)
