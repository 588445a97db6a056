"""3-D world of a biped (paper 004): box obstacles with heights, the robot's gait and body sizes.

World YAML (see ``config/worlds/biped/``)::

    name: corridor_wide
    resolution: 0.02              # metres per cell of the 2-D map
    bounds: [xmin, ymin, xmax, ymax]
    robot:
      gait_length: 0.30           # l: gait rectangle along the walking direction
      gait_width: 0.36            # w_k: gait rectangle across (what the feet cover)
      body_width: 0.50            # w_r, symmetric body; or body_left / body_right (asymmetric,
                                  #   body extent left/right of the gait centre line = δ_MR, δ_ML... see docs)
      step_height: 0.06           # higher than this the feet cannot step over / onto
      body_bottom: 0.45           # lowest point of the body above the floor (legs below)
      height: 1.20                # top of the robot
    reference_line: [[x, y], ...] # optional line S for an asymmetric body (default: start → goal)
    start: [x, y, theta]
    goal: [x, y, theta]
    obstacles:
      - {name: wall, center: [x, y], size: [sx, sy], z: [zmin, zmax], yaw: 0.0}
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from maru_planner.base.budget import MAX_MAP_CELLS
from maru_planner.errors import InvalidScene, TooLarge

MAX_OBSTACLES = 10000


@dataclass
class BipedRobot:
    """Gait rectangle (l × w_k) and body (w_r, possibly off-centre) of a biped."""

    gait_length: float = 0.30
    gait_width: float = 0.36
    body_left: float = 0.25  # body extent left of the gait centre line
    body_right: float = 0.25  # body extent right of the gait centre line
    step_height: float = 0.06
    body_bottom: float = 0.45
    height: float = 1.20

    def __post_init__(self):
        for name in ("gait_length", "gait_width", "body_left", "body_right", "height"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InvalidScene(f"robot.{name} must be a positive number, got {value}")
        if not 0 <= self.step_height <= self.body_bottom <= self.height:
            raise InvalidScene("robot heights must satisfy 0 <= step_height <= body_bottom <= height")

    @property
    def body_width(self) -> float:
        """w_r."""
        return self.body_left + self.body_right

    @property
    def symmetric(self) -> bool:
        return math.isclose(self.body_left, self.body_right)

    @property
    def overhang_left(self) -> float:
        """Clearance added on the robot's left (eq. 3: w_r − (δ_MR + w_k/2), δ_MR = body_right)."""
        return max(0.0, self.body_width - (self.body_right + self.gait_width / 2))

    @property
    def overhang_right(self) -> float:
        """Clearance added on the robot's right (eq. 2: w_r − (δ_ML + w_k/2), δ_ML = body_left)."""
        return max(0.0, self.body_width - (self.body_left + self.gait_width / 2))

    @property
    def corner_distance(self) -> float:
        """K: distance from the centre of the gait rectangle to a corner."""
        return 0.5 * math.hypot(self.gait_length, self.gait_width)


@dataclass
class Box3D:
    """An obstacle: a box of footprint ``size`` at ``center`` rotated by ``yaw``, spanning ``z``."""

    name: str
    center: tuple
    size: tuple
    z: tuple = (0.0, 2.0)
    yaw: float = 0.0

    def corners(self) -> np.ndarray:
        """(4, 2) footprint corners, counter-clockwise."""
        hx, hy = self.size[0] / 2, self.size[1] / 2
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return local @ np.array([[c, s], [-s, c]]) + np.asarray(self.center, dtype=float)


@dataclass
class BipedWorld:
    name: str
    resolution: float
    bounds: tuple
    robot: BipedRobot
    obstacles: list
    start: tuple | None = None
    goal: tuple | None = None
    reference_line: np.ndarray | None = None
    meta: dict = field(default_factory=dict)


def grid_shape(bounds: tuple, resolution: float) -> tuple[int, int]:
    """(rows, cols) of the 2-D map covering ``bounds`` at ``resolution``; TooLarge over MAX_MAP_CELLS."""
    xmin, ymin, xmax, ymax = bounds
    rows, cols = (ymax - ymin) / resolution, (xmax - xmin) / resolution
    if not rows * cols <= MAX_MAP_CELLS:  # also catches inf and nan before they become integers
        raise TooLarge(
            f"world bounds {[round(b, 3) for b in bounds]} at {resolution:.3g} m: about "
            f"{rows * cols:.3g} cells, over the limit of {MAX_MAP_CELLS} cells"
        )
    return int(math.ceil(rows - 1e-9)), int(math.ceil(cols - 1e-9))


def _floats(value, n: int, what: str) -> tuple:
    try:
        out = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise InvalidScene(f"{what} must be a list of {n} numbers, got {str(value)[:60]}") from None
    if len(out) != n or not all(math.isfinite(v) for v in out):
        raise InvalidScene(f"{what} must be {n} finite numbers, got {str(value)[:60]}")
    return out


def _robot_from(data: dict | None) -> BipedRobot:
    data = dict(data or {})
    known = {
        "gait_length",
        "gait_width",
        "body_width",
        "body_left",
        "body_right",
        "step_height",
        "body_bottom",
        "height",
    }
    unknown = set(data) - known
    if unknown:
        raise InvalidScene(f"unknown robot field(s) {str(sorted(map(str, unknown)))[:80]}; expected {sorted(known)}")
    if "body_width" in data:
        if "body_left" in data or "body_right" in data:
            raise InvalidScene("give either robot.body_width (symmetric) or body_left/body_right, not both")
        half = float(data.pop("body_width")) / 2
        data["body_left"] = data["body_right"] = half
    try:
        return BipedRobot(**{k: float(v) for k, v in data.items()})
    except (TypeError, ValueError) as exc:
        raise InvalidScene(f"robot: {str(exc)[:120]}") from None


def _box_from(i: int, data: dict) -> Box3D:
    if not isinstance(data, dict):
        raise InvalidScene(f"obstacle #{i} must be a mapping, got {str(data)[:60]}")
    name = str(data.get("name", f"obstacle_{i}"))
    label = f"obstacle {name[:40]!r}"
    for key in ("center", "size"):
        if key not in data:
            raise InvalidScene(f"{label} has no {key!r}")
    size = _floats(data["size"], 2, f"{label} size")
    if min(size) <= 0:
        raise InvalidScene(f"{label} size must be positive, got {size}")
    z = _floats(data.get("z", (0.0, 2.0)), 2, f"{label} z")
    if z[1] <= z[0]:
        raise InvalidScene(f"{label} z must be [zmin, zmax] with zmax > zmin, got {z}")
    center = _floats(data["center"], 2, f"{label} center")
    return Box3D(name, center, size, z, _floats([data.get("yaw", 0.0)], 1, f"{label} yaw")[0])


def world_from_dict(data: dict, name: str = "world") -> BipedWorld:
    if not isinstance(data, dict):
        raise InvalidScene("a biped world must be a YAML mapping")
    resolution = _floats([data.get("resolution", 0.02)], 1, "resolution")[0]
    if not resolution > 0:
        raise InvalidScene(f"resolution must be positive, got {resolution}")
    if "bounds" not in data:
        raise InvalidScene("world has no 'bounds' [xmin, ymin, xmax, ymax]")
    bounds = _floats(data["bounds"], 4, "bounds")
    if bounds[2] <= bounds[0] or bounds[3] <= bounds[1]:
        raise InvalidScene(f"bounds must be [xmin, ymin, xmax, ymax] with max > min, got {bounds}")
    grid_shape(bounds, resolution)
    raw_obstacles = data.get("obstacles") or []
    if not isinstance(raw_obstacles, list):
        raise InvalidScene(f"obstacles must be a list, got {str(raw_obstacles)[:40]}")
    if len(raw_obstacles) > MAX_OBSTACLES:
        raise InvalidScene(f"the world has {len(raw_obstacles)} obstacles, over the limit of {MAX_OBSTACLES}")
    obstacles = [_box_from(i, o) for i, o in enumerate(raw_obstacles)]
    start = _floats(data["start"], 3, "start") if "start" in data else None
    goal = _floats(data["goal"], 3, "goal") if "goal" in data else None
    line = None
    if data.get("reference_line") is not None:
        try:
            line = np.asarray(data["reference_line"], dtype=float)
        except (TypeError, ValueError):
            line = np.zeros((0,))
        if line.ndim != 2 or line.shape[1] != 2 or len(line) < 2 or not np.isfinite(line).all():
            raise InvalidScene("reference_line must be a list of at least two [x, y] points")
    return BipedWorld(
        str(data.get("name", name)),
        resolution,
        bounds,
        _robot_from(data.get("robot")),
        obstacles,
        start,
        goal,
        line,
        {k: v for k, v in data.items() if k == "description"},
    )


def load_world(path) -> BipedWorld:
    """Read a biped world YAML file (raises InvalidScene naming what is wrong)."""
    path = Path(path)
    if not path.is_file():
        raise InvalidScene(f"biped world file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None)
        line = f" (line {where.line + 1})" if where is not None else ""
        raise InvalidScene(f"{path}: not valid YAML{line}") from None
    return world_from_dict(data, path.stem)
