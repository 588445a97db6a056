"""Scene: named obstacles (box, sphere, cylinder, mesh) in the robot's root frame.

YAML schema (what benchmarks and external checks write)::

    frame: base_link
    obstacles:
      - {name: desk, type: box, size: [x, y, z], pose: {xyz: [x, y, z], rpy: [r, p, y]}}
      - {name: ball, type: sphere, radius: r, pose: {xyz: [x, y, z]}}
      - {name: post, type: cylinder, radius: r, length: l, pose: {xyz: [...], rpy: [...]}}
      - {name: part, type: mesh, path: part.stl, scale: [1, 1, 1], pose: {...}}

Box sizes are full side lengths; cylinders are along their local z, centred.
A relative mesh path is resolved against the YAML file's directory.
Every change bumps ``scene.version`` so planners can cache on it.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from maru_planner.errors import InvalidScene

OBSTACLE_TYPES = ("box", "sphere", "cylinder", "mesh")


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) (URDF / REP 103 convention)."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a rotation matrix, the inverse of :func:`rpy_matrix` (gimbal lock: all in yaw)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-9:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def _numbers(where: str, field_name: str, value: Any, count: int) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidScene(f"{where}: field '{field_name}' must be {count} numbers, got {value!r}") from None
    if arr.size != count:
        raise InvalidScene(f"{where}: field '{field_name}' must have {count} numbers, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise InvalidScene(f"{where}: field '{field_name}' contains NaN or inf: {value!r}")
    return arr


def _positive(where: str, field_name: str, value: Any) -> float:
    if value is None:
        raise InvalidScene(f"{where}: missing field '{field_name}'")
    (x,) = _numbers(where, field_name, value, 1)
    if x <= 0:
        raise InvalidScene(f"{where}: field '{field_name}' must be > 0, got {x}")
    return float(x)


def pose_matrix(pose: Any, where: str = "pose") -> np.ndarray:
    """A 4x4 from a 4x4, {xyz, rpy}, (x, y, z) or (x, y, z, roll, pitch, yaw)."""
    if pose is None:
        return np.eye(4)
    if isinstance(pose, dict):
        unknown = set(pose) - {"xyz", "rpy"}
        if unknown:
            raise InvalidScene(f"{where}: unknown pose field(s) {sorted(unknown)} (use xyz, rpy)")
        T = np.eye(4)
        T[:3, 3] = _numbers(where, "pose.xyz", pose.get("xyz", [0, 0, 0]), 3)
        T[:3, :3] = rpy_matrix(*_numbers(where, "pose.rpy", pose.get("rpy", [0, 0, 0]), 3))
        return T
    arr = np.asarray(pose, dtype=float)
    if arr.shape == (4, 4):
        if not np.all(np.isfinite(arr)):
            raise InvalidScene(f"{where}: pose contains NaN or inf")
        R = arr[:3, :3]
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise InvalidScene(f"{where}: pose rotation is not a rotation matrix")
        return arr.copy()
    flat = arr.reshape(-1)
    if flat.size == 3:
        T = np.eye(4)
        T[:3, 3] = _numbers(where, "pose", flat, 3)
        return T
    if flat.size == 6:
        vals = _numbers(where, "pose", flat, 6)
        T = np.eye(4)
        T[:3, 3], T[:3, :3] = vals[:3], rpy_matrix(*vals[3:])
        return T
    raise InvalidScene(f"{where}: pose must be a 4x4, {{xyz, rpy}}, xyz or xyz+rpy, got shape {arr.shape}")


@dataclass
class Obstacle:
    """One named obstacle; validated on creation (raises InvalidScene)."""

    name: str
    type: str
    size: tuple[float, float, float] | None = None  # box: full side lengths
    radius: float | None = None  # sphere, cylinder
    length: float | None = None  # cylinder (along local z)
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))
    path: str | None = None  # mesh file
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)  # mesh

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise InvalidScene(f"obstacle {self.name!r}: field 'name' must be a non-empty string")
        where = f"obstacle '{self.name}'"
        if self.type not in OBSTACLE_TYPES:
            raise InvalidScene(f"{where}: field 'type' must be one of {OBSTACLE_TYPES}, got {self.type!r}")
        self.pose = pose_matrix(self.pose, where)
        if self.type == "box":
            if self.size is None:
                raise InvalidScene(f"{where}: missing field 'size'")
            size = _numbers(where, "size", self.size, 3)
            if np.any(size <= 0):
                raise InvalidScene(f"{where}: field 'size' must be > 0, got {size.tolist()}")
            self.size = tuple(float(v) for v in size)
        elif self.type in ("sphere", "cylinder"):
            self.radius = _positive(where, "radius", self.radius)
            if self.type == "cylinder":
                self.length = _positive(where, "length", self.length)
        else:
            if not self.path:
                raise InvalidScene(f"{where}: missing field 'path'")
            scale = _numbers(where, "scale", self.scale, 3)
            if np.any(scale <= 0):
                raise InvalidScene(f"{where}: field 'scale' must be > 0")
            self.scale = tuple(float(v) for v in scale)

    @classmethod
    def from_dict(cls, d: dict, base_dir: Path | None = None) -> Obstacle:
        if not isinstance(d, dict):
            raise InvalidScene(f"obstacle entry must be a mapping, got {d!r}")
        name = d.get("name")
        allowed = {"name", "type", "size", "radius", "length", "pose", "path", "scale"}
        unknown = set(d) - allowed
        if unknown:
            raise InvalidScene(f"obstacle {name!r}: unknown field(s) {sorted(unknown)}")
        if "type" not in d:
            raise InvalidScene(f"obstacle {name!r}: missing field 'type'")
        path = d.get("path")
        if path is not None and base_dir is not None and not Path(path).is_absolute():
            path = str(base_dir / path)
        return cls(
            name=name,
            type=d["type"],
            size=d.get("size"),
            radius=d.get("radius"),
            length=d.get("length"),
            pose=d.get("pose"),
            path=path,
            scale=d.get("scale", (1.0, 1.0, 1.0)),
        )

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"name": self.name, "type": self.type}
        if self.type == "box":
            d["size"] = list(self.size)
        if self.type in ("sphere", "cylinder"):
            d["radius"] = self.radius
        if self.type == "cylinder":
            d["length"] = self.length
        if self.type == "mesh":
            d["path"], d["scale"] = self.path, list(self.scale)
        d["pose"] = {"xyz": self.pose[:3, 3].tolist(), "rpy": list(matrix_rpy(self.pose[:3, :3]))}
        return d


def _is_file(text: str) -> bool:
    try:
        return Path(text).is_file()
    except (OSError, ValueError):  # e.g. a long one-line YAML string is not a valid file name
        return False


class Scene:
    """An ordered set of named obstacles in ``frame`` (the robot's root frame)."""

    def __init__(self, obstacles: list[Obstacle] | None = None, frame: str = "base_link"):
        self.frame = frame
        self.obstacles: OrderedDict[str, Obstacle] = OrderedDict()
        self.version = 0
        for obstacle in obstacles or []:
            self.add(obstacle)

    # ------------------------------------------------------------ editing --
    def add(self, obstacle: Obstacle) -> None:
        """Add (or replace, keeping its position in the order) an obstacle."""
        if not isinstance(obstacle, Obstacle):
            raise InvalidScene(f"expected an Obstacle, got {type(obstacle).__name__}")
        self.obstacles[obstacle.name] = obstacle
        self.version += 1

    def move(self, name: str, pose: Any) -> None:
        """Set an obstacle's pose (4x4, xyz, xyz+rpy or {xyz, rpy})."""
        obstacle = self._get(name)
        obstacle.pose = pose_matrix(pose, f"obstacle '{name}'")
        self.version += 1

    def remove(self, name: str) -> None:
        self._get(name)
        del self.obstacles[name]
        self.version += 1

    def clear(self) -> None:
        self.obstacles.clear()
        self.version += 1

    def _get(self, name: str) -> Obstacle:
        if name not in self.obstacles:
            raise InvalidScene(f"obstacle '{name}': not in the scene (have {list(self.obstacles)})")
        return self.obstacles[name]

    def __len__(self) -> int:
        return len(self.obstacles)

    def __contains__(self, name: str) -> bool:
        return name in self.obstacles

    # ---------------------------------------------------------------- I/O --
    @classmethod
    def from_dict(cls, d: dict | None, base_dir: Path | None = None) -> Scene:
        if d is None:
            return cls()
        if not isinstance(d, dict):
            raise InvalidScene(f"scene must be a mapping with 'obstacles', got {type(d).__name__}")
        unknown = set(d) - {"frame", "obstacles"}
        if unknown:
            raise InvalidScene(f"scene: unknown field(s) {sorted(unknown)}")
        entries = d.get("obstacles") or []
        if not isinstance(entries, list):
            raise InvalidScene("scene: field 'obstacles' must be a list")
        obstacles = [Obstacle.from_dict(e, base_dir) for e in entries]
        names = [o.name for o in obstacles]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise InvalidScene(f"scene: duplicate obstacle name(s) {dupes}")
        return cls(obstacles, frame=str(d.get("frame", "base_link")))

    @classmethod
    def from_yaml(cls, source: str | Path) -> Scene:
        """Load from a YAML file path or a YAML string."""
        base_dir = None
        text = str(source)
        one_line = "\n" not in text
        is_path = isinstance(source, Path) or (one_line and (text.endswith((".yaml", ".yml")) or _is_file(text)))
        if is_path:
            path = Path(source)
            if not path.is_file():
                raise InvalidScene(f"scene file not found: {path}")
            text, base_dir = path.read_text(), path.parent
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            raise InvalidScene(f"scene YAML does not parse: {exc}") from None
        return cls.from_dict(data, base_dir)

    def to_dict(self) -> dict:
        return {"frame": self.frame, "obstacles": [o.to_dict() for o in self.obstacles.values()]}

    def to_yaml(self) -> str:
        return yaml.safe_dump(self.to_dict(), sort_keys=False)

    def __repr__(self) -> str:
        return f"Scene({list(self.obstacles)}, version={self.version})"
