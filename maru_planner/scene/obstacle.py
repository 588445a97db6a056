"""Obstacles: a named shape of the shape table at a pose, and an obstacle attached to a robot link.

An obstacle's fields are its shape's dimensions (:mod:`maru_planner.scene.shapes`), validated on
creation with one-line InvalidScene errors naming the obstacle and the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import coal
import numpy as np

from maru_planner.errors import InvalidScene
from maru_planner.scene.poses import matrix_rpy, pose_matrix
from maru_planner.scene.shapes import KernelPrimitive, ShapeSpec, posed, shape, validate

MAX_NAME_LENGTH = 256  # characters of an obstacle name


class Obstacle:
    """One named obstacle of a registered shape (:mod:`maru_planner.scene.shapes`); validated on creation.

    ``Obstacle("desk", "box", size=(1, 2, 0.1), pose=[0.5, 0, 0])``: the keyword fields are the shape's
    dimensions and are readable as attributes (``desk.size``); bad values raise InvalidScene.
    """

    def __init__(self, name: str, type: str, pose: Any = None, **dimensions: Any):
        if not isinstance(name, str) or not name:
            raise InvalidScene(f"obstacle {name!r:.60}: field 'name' must be a non-empty string")
        if len(name) > MAX_NAME_LENGTH:
            raise InvalidScene(f"obstacle name {name!r:.60} has {len(name)} characters, more than {MAX_NAME_LENGTH}")
        where = f"obstacle {name[:60]!r}"  # repr of an excerpt: one line, a bounded message
        self.name = name
        self.type: str = type
        self.pose = pose_matrix(pose, where)
        self.dimensions = validate(shape(type, where), where, dimensions)

    @property
    def spec(self) -> ShapeSpec:
        """The shape's table entry (looked up, not stored: obstacles pickle as plain data)."""
        return shape(self.type, f"obstacle '{self.name}'")

    def __getattr__(self, field_name: str) -> Any:
        dimensions = self.__dict__.get("dimensions", {})
        if field_name in dimensions:
            return dimensions[field_name]
        raise AttributeError(f"{type(self).__name__} '{self.__dict__.get('name')}' has no field {field_name!r}")

    def geometry(self) -> coal.CollisionGeometry:
        """The exact coal shape, in the obstacle's frame."""
        return self.spec.geometry(self.dimensions)

    def kernel_primitive(self) -> KernelPrimitive:
        """The sphere checker's primitive (the shape itself, or a box that bounds it), in the scene frame."""
        return self.spec.kernel_primitive(self.dimensions, self.pose)

    def faces(self) -> list[np.ndarray]:
        """Polygons of the obstacle's surface in the scene frame (for pictures)."""
        return posed(self.spec.faces(self.dimensions), self.pose)

    @classmethod
    def from_dict(cls, d: dict, base_dir: Path | None = None) -> Obstacle:
        if not isinstance(d, dict):
            raise InvalidScene(f"obstacle entry must be a mapping, got {d!r:.60}")
        name: Any = d.get("name")  # Obstacle checks it
        if "type" not in d:
            raise InvalidScene(f"obstacle {name!r:.60}: missing field 'type'")
        spec = shape(d["type"], f"obstacle {name!r:.60}")
        dimensions = {k: v for k, v in d.items() if k not in ("name", "type", "pose")}
        for dim in spec.dimensions:
            value = dimensions.get(dim.name)
            if dim.is_path and isinstance(value, str) and base_dir is not None and not Path(value).is_absolute():
                dimensions[dim.name] = str(base_dir / value)
        return cls(name, d["type"], pose=d.get("pose"), **dimensions)

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"name": self.name, "type": self.type}
        for key, value in self.dimensions.items():
            d[key] = list(value) if isinstance(value, tuple) else value
        d["pose"] = {"xyz": self.pose[:3, 3].tolist(), "rpy": list(matrix_rpy(self.pose[:3, :3]))}
        return d

    def __repr__(self) -> str:
        fields = ", ".join(f"{k}={v!r}" for k, v in self.dimensions.items())
        return f"Obstacle({self.name!r}, {self.type!r}, {fields}, xyz={self.pose[:3, 3].tolist()})"


class AttachedObject:
    """An obstacle fixed to a robot link: ``obstacle.pose`` is in the link's frame."""

    def __init__(self, obstacle: Obstacle, link: Any, touch_links: Any = ()):
        where = f"attached object '{obstacle.name}'"
        if not isinstance(link, str) or not link:
            raise InvalidScene(f"{where}: field 'link' must be a link name, got {link!r}")
        if isinstance(touch_links, str) or not all(isinstance(t, str) and t for t in touch_links):
            raise InvalidScene(f"{where}: field 'touch_links' must be a list of link names, got {touch_links!r}")
        self.obstacle, self.link, self.touch_links = obstacle, link, tuple(dict.fromkeys(touch_links))

    @property
    def name(self) -> str:
        return self.obstacle.name

    def key(self) -> tuple:
        """Everything that shapes the robot's collision model (equal keys: the same attached geometry)."""
        dims = tuple(sorted((k, str(v)) for k, v in self.obstacle.dimensions.items()))
        pose = tuple(np.round(self.obstacle.pose, 12).ravel())
        return (self.name, self.obstacle.type, dims, pose, self.link, self.touch_links)

    @classmethod
    def from_dict(cls, d: dict, base_dir: Path | None = None) -> AttachedObject:
        if not isinstance(d, dict):
            raise InvalidScene(f"attached entry must be a mapping, got {d!r}")
        fields = {k: v for k, v in d.items() if k not in ("link", "touch_links")}
        return cls(Obstacle.from_dict(fields, base_dir), d.get("link"), d.get("touch_links") or ())

    def to_dict(self) -> dict:
        return {**self.obstacle.to_dict(), "link": self.link, "touch_links": list(self.touch_links)}
