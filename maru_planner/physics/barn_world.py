"""One BARN world as MJCF: the 30 x 30 field's cylinders, the containment walls and a floor, in the challenge's frame.

Frames (the dataset's README, from the world files): field cell (r, c) is the cylinder at
x = -4.425 + 0.15 r, y = 5.175 + 0.15 c (r 0.075 m, h 1 m). The containment walls are cylinders too:
the back wall at y = 0.075 for every row, side walls at x = -0.075 and x = -4.425 for y = 0.225 .. 5.025.
In the dataset's ``full_grid`` (30 x 94) form, cell (r, c) is centred at x = -4.5 + 0.15 (r + 0.5),
y = 0.15 (c + 0.5) and the field occupies columns 34 .. 63.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from maru_planner.errors import InvalidMap, InvalidRequest
from maru_planner.paths import benchmarks_dir

CELL = 0.15  # m
CYLINDER_RADIUS = 0.075  # m
CYLINDER_HEIGHT = 1.0  # m
GRID_SHAPE = (30, 30)
FULL_COLUMNS = 94
FIELD_FIRST_COLUMN = 34
WORLD_COUNT = 300
START = (-2.25, 3.0, math.pi / 2)  # run.py INIT_POSITION
GOAL = (-2.25, 13.0)  # start + (0, 10)
OBSTACLE_GROUP = 1  # MJCF geom group of the cylinders (the laser sees only this group)


def barn_dir() -> Path:
    return benchmarks_dir() / "barn"


def check_grid(grid: object, name: str = "grid") -> np.ndarray:
    """A (30, 30) grid of 0/1 (uint8 or bool) as uint8; InvalidMap naming what is wrong otherwise."""
    array = np.asarray(grid)
    if array.shape != GRID_SHAPE:
        raise InvalidMap(f"{name} must have shape (30, 30) like the dataset's grid_files, got {array.shape}")
    if array.dtype not in (np.uint8, np.bool_):
        raise InvalidMap(f"{name} must be uint8 (1 = cylinder) like the dataset's grid_files, got dtype {array.dtype}")
    if array.dtype == np.uint8 and int(array.max(initial=0)) > 1:
        raise InvalidMap(f"{name} must hold only 0 and 1 (1 = cylinder), got a value {int(array.max())}")
    return array.astype(np.uint8)


def load_grid(path: str | Path) -> np.ndarray:
    """A grid file (``.npy``, the dataset's ``grid_files`` format); InvalidRequest naming the file on any problem."""
    try:
        array = np.load(Path(path), allow_pickle=False)
    except (OSError, ValueError, EOFError) as exc:
        raise InvalidRequest(f"cannot read grid file {path}: {str(exc).splitlines()[0][:120]}") from None
    return check_grid(array, f"grid file {path}")


def world_grid(index: int) -> np.ndarray:
    """The public world ``index`` (0 .. 299) from the dataset's grid_files."""
    if not (isinstance(index, int) and 0 <= index < WORLD_COUNT):
        raise InvalidRequest(f"BARN world must be an integer 0..{WORLD_COUNT - 1}, got {index}")
    path = barn_dir() / "grid_files" / f"grid_{index}.npy"
    if not path.is_file():
        raise InvalidRequest(f"BARN data not found: {path} (set MARU_BENCHMARKS_DIR)")
    return load_grid(path)


@cache
def _optimal_times() -> dict[int, float]:
    with open(barn_dir() / "worlds.csv") as f:
        return {int(row["world"]): float(row["optimal_time_s"]) for row in csv.DictReader(f)}


def optimal_time(index: int) -> float:
    """The challenge's optimal time of world ``index`` (worlds.csv: path length / 2 m/s)."""
    return _optimal_times()[index]


def full_grid(grid: np.ndarray) -> np.ndarray:
    """Field plus containment walls as the dataset's (30, 94) ``full_grid`` (1 = cylinder)."""
    full = np.zeros((GRID_SHAPE[0], FULL_COLUMNS), dtype=np.uint8)
    full[:, FIELD_FIRST_COLUMN : FIELD_FIRST_COLUMN + GRID_SHAPE[1]] = check_grid(grid)
    full[:, 0] = 1  # back wall, y = 0.075
    full[0, 1:FIELD_FIRST_COLUMN] = 1  # side wall x = -4.425
    full[-1, 1:FIELD_FIRST_COLUMN] = 1  # side wall x = -0.075
    return full


def full_cell_centres(cells: np.ndarray) -> np.ndarray:
    """(n, 2) full-grid (row, col) -> (n, 2) world (x, y) of the cylinder centres."""
    cells = np.asarray(cells, dtype=float).reshape(-1, 2)
    return np.column_stack([-4.5 + CELL * (cells[:, 0] + 0.5), CELL * (cells[:, 1] + 0.5)])


def cylinder_centres(grid: np.ndarray) -> np.ndarray:
    """World (x, y) of every cylinder of the world: field and containment walls."""
    return full_cell_centres(np.argwhere(full_grid(grid)))


@dataclass(frozen=True)
class WorldXml:
    """Parts of the MJCF document a robot model adds to a world."""

    robot_body: str  # one <body> under <worldbody>
    actuators: str  # the <actuator> children
    extra_assets: str = ""


def world_mjcf(grid: np.ndarray, robot: WorldXml, timestep: float, name: str = "barn") -> str:
    """The MJCF document of one world with ``robot`` in it."""
    centres = cylinder_centres(grid)
    half = CYLINDER_HEIGHT / 2
    cylinders = "\n".join(
        f'    <geom name="cyl{i}" class="obstacle" pos="{x:.4f} {y:.4f} {half}"/>' for i, (x, y) in enumerate(centres)
    )
    return f"""<mujoco model="{name}">
  <option timestep="{timestep}" integrator="implicitfast" cone="elliptic" impratio="10"/>
  <default>
    <default class="obstacle">
      <geom type="cylinder" size="{CYLINDER_RADIUS} {half}" group="{OBSTACLE_GROUP}" rgba="0.6 0.4 0.2 1"
            contype="2" conaffinity="1"/>
    </default>
  </default>
  <asset>{robot.extra_assets}</asset>
  <worldbody>
    <geom name="floor" type="plane" size="20 20 0.1" pos="-2.25 7 0" contype="1" conaffinity="1" group="0"
          friction="0.1 0.005 0.0001"/>
{cylinders}
{robot.robot_body}
  </worldbody>
  <actuator>
{robot.actuators}
  </actuator>
</mujoco>
"""
