"""World files for the 2-D simulator (YAML) and ROS map_server occupancy maps (YAML + PGM).

```yaml
name: goal_behind_obstacle
map: maps/room.yaml            # optional, map_server YAML, relative to this file
obstacles:
  - {type: circle, center: [4.0, 0.0], radius: 0.5}
  - {type: box, center: [6.0, 1.0], size: [0.6, 0.4], yaw: 0.3}
  - {type: polygon, points: [[1, 1], [2, 1], [1.5, 2]]}
movers:                        # circles moving along waypoints
  - {radius: 0.25, speed: 1.2, waypoints: [[5, -4], [5, 4]], start_time: 1.0, mode: stop}  # or loop / pingpong
robot:
  start: [0.0, 0.0, 0.0]
  goal: [8.0, 0.0, 0.0]
  radius: 0.30                 # or footprint: [[x, y], ...] (polygon in base_link)
  max_linear: 0.5
  max_angular: 1.0
  laser: {x: 0.22, y: 0.0, yaw: 0.0, fov_deg: 180, resolution_deg: 0.5, range_min: 0.05, range_max: 10.0,
          noise: 0.01, rate: 20}
path: [[0, 0], [8, 0]]         # optional initial path (default: straight line start -> goal)
goal_tolerance: 0.3            # success radius
max_time: 60.0
bounds: [-1, -3, 9, 3]         # optional, for pictures
```
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy.ndimage import distance_transform_edt

from maru_planner.base.grid import OccupancyGrid
from maru_planner.errors import InvalidScene, MaruError, one_line
from maru_planner.reactive.inputs import MAX_COORDINATE, MAX_PATH_POSES
from maru_planner.reactive.scan import MAX_SCAN_BEAMS
from maru_planner.sim.geometry import box_polygon, polygon_segments

MAX_LASER_RATE = 200.0  # Hz: simulated steps per second
MAX_SIM_TIME = 3600.0  # s of simulated time in one run


class WorldError(InvalidScene):
    """A world file is malformed; the message names the entry and field."""

    source = "world"


@dataclass
class OccupancyMap:
    """A map_server occupancy grid: ``occupied[row, col]``, row 0 at the bottom (origin side)."""

    occupied: np.ndarray
    resolution: float
    origin: tuple[float, float]

    @classmethod
    def from_yaml(cls, path: str | Path) -> OccupancyMap:
        """Read a map_server map with the base planners' reader; unknown cells are free here."""
        path = Path(path)
        try:
            grid = OccupancyGrid.from_yaml(path, unknown_is_occupied=False)
        except (OSError, ValueError, yaml.YAMLError, MaruError) as exc:
            raise WorldError(f"map {path}: cannot read ({exc})") from exc
        return cls(grid.occupied, grid.resolution, grid.origin[:2])

    def cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        col = np.floor((points[..., 0] - self.origin[0]) / self.resolution).astype(int)
        row = np.floor((points[..., 1] - self.origin[1]) / self.resolution).astype(int)
        inside = (row >= 0) & (row < self.occupied.shape[0]) & (col >= 0) & (col < self.occupied.shape[1])
        return row, col, inside

    def is_occupied(self, points: np.ndarray) -> np.ndarray:
        row, col, inside = self.cells(points)
        out = np.zeros(row.shape, dtype=bool)
        out[inside] = self.occupied[row[inside], col[inside]]
        return out

    def distance_field(self) -> np.ndarray:
        """Metres from each cell centre to the nearest occupied cell's edge (0 inside occupied cells)."""
        if not np.any(self.occupied):
            return np.full(self.occupied.shape, np.inf)
        d = distance_transform_edt(~self.occupied) * self.resolution
        return np.where(self.occupied, 0.0, np.maximum(d - 0.5 * self.resolution, 0.0))


@dataclass
class Mover:
    """A circle moving along waypoints at ``speed`` from ``start_time`` (mode stop / loop / pingpong)."""

    radius: float
    speed: float
    waypoints: np.ndarray
    start_time: float = 0.0
    mode: str = "stop"
    _cum: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        seg = np.hypot(*np.diff(self.waypoints, axis=0).T)
        self._cum = np.concatenate([[0.0], np.cumsum(seg)])

    def position(self, t: float, time_offset: float = 0.0) -> np.ndarray:
        total = self._cum[-1]
        s = max(t - self.start_time - time_offset, 0.0) * self.speed
        if total <= 0:
            return self.waypoints[0].copy()
        if self.mode == "loop":
            s = s % total
        elif self.mode == "pingpong":
            s = s % (2 * total)
            s = 2 * total - s if s > total else s
        else:
            s = min(s, total)
        return np.array([np.interp(s, self._cum, self.waypoints[:, 0]), np.interp(s, self._cum, self.waypoints[:, 1])])


@dataclass
class LaserSpec:
    """Laser geometry; defaults: SICK LMS200 (180 deg, 0.5 deg, 10 m) at 20 Hz."""

    x: float = 0.22
    y: float = 0.0
    yaw: float = 0.0
    fov_deg: float = 180.0
    resolution_deg: float = 0.5
    range_min: float = 0.05
    range_max: float = 10.0
    noise: float = 0.01
    rate: float = 20.0

    @property
    def beams(self) -> int:
        return int(round(self.fov_deg / self.resolution_deg)) + 1


@dataclass
class RobotSpec:
    start: np.ndarray
    goal: np.ndarray
    radius: float = 0.30
    footprint: np.ndarray | None = None  # polygon in base_link; None = circle of ``radius``
    max_linear: float = 0.5
    max_angular: float = 1.0
    laser: LaserSpec = field(default_factory=LaserSpec)

    @property
    def bounding_radius(self) -> float:
        if self.footprint is None:
            return self.radius
        return float(np.max(np.hypot(self.footprint[:, 0], self.footprint[:, 1])))


@dataclass
class World:
    """Static shapes, optional occupancy map, movers and the robot's task."""

    robot: RobotSpec
    circles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    polygons: list = field(default_factory=list)
    movers: list = field(default_factory=list)
    occupancy: OccupancyMap | None = None
    path: np.ndarray | None = None
    goal_tolerance: float = 0.3
    max_time: float = 60.0
    name: str = "world"
    bounds: tuple | None = None
    segments: np.ndarray = field(init=False)

    def __post_init__(self):
        self.circles = np.asarray(self.circles, dtype=float).reshape(-1, 3)
        segs = [polygon_segments(p) for p in self.polygons]
        self.segments = np.vstack(segs) if segs else np.zeros((0, 4))

    @classmethod
    def from_yaml(cls, path: str | Path) -> World:
        path = Path(path)
        try:
            data = yaml.safe_load(path.read_text())
        except OSError as exc:
            raise WorldError(f"world {path}: cannot read ({exc})") from exc
        except yaml.YAMLError as exc:
            raise WorldError(f"world {path}: invalid YAML ({one_line(exc, 160)})") from exc
        return cls.from_dict(data, base_dir=path.parent, name=path.stem)

    @classmethod
    def from_dict(cls, data, base_dir: Path | None = None, name: str = "world") -> World:
        if not isinstance(data, dict):
            raise WorldError("world: expected a mapping at the top level")
        unknown = set(data) - {
            "name",
            "description",
            "map",
            "obstacles",
            "movers",
            "robot",
            "path",
            "goal_tolerance",
            "max_time",
            "bounds",
        }
        if unknown:
            raise WorldError(f"world: unknown field(s) {sorted(unknown)}")
        if "robot" not in data:
            raise WorldError("world: missing field 'robot' (with start and goal)")
        circles: list[tuple[float, float, float]] = []
        polygons: list[np.ndarray] = []
        for i, entry in enumerate(_entries(data, "obstacles")):
            kind, shape = _parse_obstacle(entry, f"obstacles[{i}]")
            (circles if kind == "circle" else polygons).append(shape)
        movers = [_parse_mover(m, f"movers[{i}]") for i, m in enumerate(_entries(data, "movers"))]
        occupancy = None
        if data.get("map"):
            if not isinstance(data["map"], str):
                raise WorldError(f"map: expected a file name, got {data['map']!r:.40}")
            map_path = Path(data["map"])
            if not map_path.is_absolute() and base_dir is not None:
                map_path = base_dir / map_path
            occupancy = OccupancyMap.from_yaml(map_path)
        path = None if data.get("path") is None else _path(data["path"])
        bounds = tuple(_array(data["bounds"], "bounds", size=4)) if data.get("bounds") is not None else None
        return cls(
            robot=_parse_robot(data["robot"]),
            circles=np.array(circles).reshape(-1, 3),
            polygons=polygons,
            movers=movers,
            occupancy=occupancy,
            path=path,
            goal_tolerance=_positive(data.get("goal_tolerance", 0.3), "goal_tolerance"),
            max_time=_positive(data.get("max_time", 60.0), "max_time", upper=MAX_SIM_TIME),
            name=str(data.get("name", name)),
            bounds=bounds,
        )

    def circles_at(self, t: float, time_offset: float = 0.0) -> np.ndarray:
        """Static circles plus the movers' circles at time ``t``."""
        if not self.movers:
            return self.circles
        moving = np.array([[*m.position(t, time_offset), m.radius] for m in self.movers])
        return np.vstack([self.circles, moving])


def _entries(data: dict, key: str) -> list:
    entries = data.get(key) or []
    if not isinstance(entries, list):
        raise WorldError(f"{key}: expected a list, got {entries!r:.40}")
    return entries


def _array(value, what: str, size: int | None = None, cols: tuple | None = None) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise WorldError(f"{what}: expected numbers, got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise WorldError(f"{what}: contains NaN or inf")
    if size is not None and arr.shape != (size,):
        raise WorldError(f"{what}: expected {size} numbers, got {value!r}")
    if cols is not None and (arr.ndim != 2 or arr.shape[1] not in cols or arr.shape[0] < 1):
        raise WorldError(f"{what}: expected a list of points with {cols} coordinates, got shape {arr.shape}")
    return arr


def _path(value) -> np.ndarray:
    """An initial path: 2 to MAX_PATH_POSES points (x, y[, yaw]) within MAX_COORDINATE of the origin."""
    if isinstance(value, list) and len(value) > MAX_PATH_POSES:  # before converting them
        raise WorldError(f"path: {len(value)} points, more than {MAX_PATH_POSES}")
    path = _array(value, "path", cols=(2, 3))
    if len(path) < 2:
        raise WorldError(f"path: needs at least 2 points (a start and an end), got {len(path)}")
    if np.abs(path[:, :2]).max() > MAX_COORDINATE:
        raise WorldError(f"path: a point is farther than {MAX_COORDINATE:g} m from the origin")
    return path


def _number(value, what: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise WorldError(f"{what}: expected a number, got {value!r:.40}") from None
    if not math.isfinite(v):
        raise WorldError(f"{what}: must be finite, got {value!r:.40}")
    return v


def _positive(value, what: str, upper: float = math.inf) -> float:
    v = _number(value, what)
    if v <= 0 or v > upper:
        raise WorldError(f"{what}: must be > 0{f' and <= {upper:g}' if math.isfinite(upper) else ''}, got {value!r}")
    return v


def _parse_obstacle(entry, what: str):
    if not isinstance(entry, dict) or "type" not in entry:
        raise WorldError(f"{what}: expected a mapping with a 'type' (circle, box, polygon)")
    kind = entry["type"]
    if kind == "circle":
        if "center" not in entry or "radius" not in entry:
            raise WorldError(f"{what}: circle needs 'center' and 'radius'")
        c = _array(entry["center"], f"{what}.center", size=2)
        return "circle", (c[0], c[1], _positive(entry["radius"], f"{what}.radius"))
    if kind == "box":
        if "center" not in entry or "size" not in entry:
            raise WorldError(f"{what}: box needs 'center' and 'size'")
        size = _array(entry["size"], f"{what}.size", size=2)
        if np.any(size <= 0):
            raise WorldError(f"{what}.size: must be > 0, got {entry['size']!r}")
        yaw = _number(entry.get("yaw", 0.0), f"{what}.yaw")
        return "polygon", box_polygon(_array(entry["center"], f"{what}.center", size=2), size, yaw)
    if kind == "polygon":
        pts = _array(entry.get("points"), f"{what}.points", cols=(2,))
        if len(pts) < 3:
            raise WorldError(f"{what}.points: a polygon needs at least 3 points")
        return "polygon", pts
    raise WorldError(f"{what}.type: unknown obstacle type {kind!r} (circle, box, polygon)")


def _parse_mover(entry, what: str) -> Mover:
    if not isinstance(entry, dict):
        raise WorldError(f"{what}: expected a mapping")
    pts = _array(entry.get("waypoints"), f"{what}.waypoints", cols=(2,))
    if len(pts) < 2:
        raise WorldError(f"{what}.waypoints: need at least 2 waypoints")
    mode = entry.get("mode", "stop")
    if mode not in ("stop", "loop", "pingpong"):
        raise WorldError(f"{what}.mode: must be stop, loop or pingpong, got {mode!r}")
    return Mover(
        radius=_positive(entry.get("radius", 0.25), f"{what}.radius"),
        speed=_positive(entry.get("speed", 1.2), f"{what}.speed"),
        waypoints=pts,
        start_time=_number(entry.get("start_time", 0.0), f"{what}.start_time"),
        mode=mode,
    )


def _parse_robot(entry) -> RobotSpec:
    if not isinstance(entry, dict):
        raise WorldError("robot: expected a mapping with start and goal")
    for key in ("start", "goal"):
        if key not in entry:
            raise WorldError(f"robot: missing field '{key}' ([x, y, theta])")
    start = _array(entry["start"], "robot.start", size=3)
    goal = _array(entry["goal"], "robot.goal", size=3)
    footprint = None
    if entry.get("footprint") is not None:
        footprint = _array(entry["footprint"], "robot.footprint", cols=(2,))
        if len(footprint) < 3:
            raise WorldError("robot.footprint: a polygon needs at least 3 points")
    laser_entry = entry.get("laser") or {}
    if not isinstance(laser_entry, dict):
        raise WorldError("robot.laser: expected a mapping")
    valid = set(LaserSpec.__dataclass_fields__)
    unknown = set(laser_entry) - valid
    if unknown:
        raise WorldError(f"robot.laser: unknown field(s) {sorted(unknown)}")
    laser = _parse_laser(laser_entry)
    return RobotSpec(
        start=start,
        goal=goal,
        radius=_positive(entry.get("radius", 0.30), "robot.radius"),
        footprint=footprint,
        max_linear=_positive(entry.get("max_linear", 0.5), "robot.max_linear"),
        max_angular=_positive(entry.get("max_angular", 1.0), "robot.max_angular"),
        laser=laser,
    )


def _parse_laser(entry: dict) -> LaserSpec:
    laser = LaserSpec(**{k: _number(v, f"robot.laser.{k}") for k, v in entry.items()})
    _positive(laser.fov_deg, "robot.laser.fov_deg", upper=360.0)
    _positive(laser.resolution_deg, "robot.laser.resolution_deg")
    _positive(laser.rate, "robot.laser.rate", upper=MAX_LASER_RATE)
    if laser.range_min < 0.0 or laser.range_max <= laser.range_min:
        raise WorldError(
            f"robot.laser: need 0 <= range_min < range_max, got range_min {laser.range_min:g}, "
            f"range_max {laser.range_max:g}"
        )
    if laser.noise < 0.0:
        raise WorldError(f"robot.laser.noise: must be >= 0, got {laser.noise:g}")
    if laser.beams > MAX_SCAN_BEAMS:
        raise WorldError(f"robot.laser: {laser.beams} beams (fov_deg / resolution_deg) is over {MAX_SCAN_BEAMS}")
    return laser
