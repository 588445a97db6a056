"""Obstacle shapes, one table: adding an obstacle type is one :class:`ShapeSpec` in :data:`SHAPES`.

Each entry says everything the rest of the package needs to know about a shape:

- its YAML/dict fields (:class:`Dimension`: name, how many numbers, default, file path or not), which
  :func:`validate` checks with one-line errors naming the obstacle and the field;
- its exact coal geometry (``geometry``, in the shape's own frame);
- its primitive for the sphere checker's kernels (``kernel_primitive``: a box, sphere or cylinder that
  is the shape or, flagged ``exact=False``, bounds it);
- its picture (``faces``: polygons in the shape frame, drawn by ``viz``);
- its ROS forms as plain data, so the ROS adapters only look them up: the ``shape_msgs/SolidPrimitive``
  constant name and the order of its ``dimensions`` (``primitive_type``, ``primitive_dimensions``), and
  the ``visualization_msgs/Marker`` constant name and scale (``marker``).

Shapes are centred on their frame; cylinders (and cones) lie along the local z axis.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np

from maru_planner.errors import InvalidScene

Dimensions = dict[str, Any]  # validated field values: floats, 3-tuples of floats, path strings
KERNEL_KINDS = ("box", "sphere", "cylinder")  # what the sphere checker's kernels test exactly
MAX_DIMENSION = 1e3  # m: largest obstacle dimension (side, radius, length) and mesh scale factor


@dataclass(frozen=True)
class Dimension:
    """One field of a shape: ``count`` positive numbers (1: a float, else a tuple) or a file path."""

    name: str
    count: int = 1
    default: Any = None  # None: required
    is_path: bool = False  # a file name, resolved against the scene file's directory


@dataclass(frozen=True)
class KernelPrimitive:
    """A primitive the sphere kernels test: a box, a sphere or a cylinder (along its local z)."""

    kind: str  # one of KERNEL_KINDS
    center: np.ndarray  # (3,) in the scene frame
    rotation: np.ndarray  # (3, 3) scene-from-primitive
    half_extents: np.ndarray  # (3,) box: half sides; sphere: (r, r, r); cylinder: (r, r, half length)
    exact: bool = True  # False: only bounds the shape, so touching it never decides a collision alone

    @property
    def origin_distance(self) -> float:
        """How near the primitive's bounding sphere comes to the scene origin (negative: it contains it)."""
        return math.hypot(*self.center) - math.hypot(*self.half_extents)


@dataclass(frozen=True)
class MarkerShape:
    """``visualization_msgs/Marker`` fields of a shape: constant name of the type, scale, mesh file."""

    type: str
    scale: tuple[float, float, float]
    mesh_resource: str = ""


@dataclass(frozen=True)
class ShapeSpec:
    """Everything about one obstacle type (see the module docstring)."""

    name: str
    dimensions: tuple[Dimension, ...]
    geometry: Callable[[Dimensions], coal.CollisionGeometry]
    kernel_primitive: Callable[[Dimensions, np.ndarray], KernelPrimitive]  # (dimensions, 4x4 pose)
    faces: Callable[[Dimensions], list[np.ndarray]]  # polygons (k, 3) in the shape frame
    marker: Callable[[Dimensions], MarkerShape]
    primitive_type: str | None = None  # shape_msgs/SolidPrimitive constant name; None: not a primitive
    primitive_dimensions: tuple[str, ...] = ()  # fields, in SolidPrimitive.dimensions order

    @property
    def field_names(self) -> tuple[str, ...]:
        return tuple(d.name for d in self.dimensions)

    def primitive_values(self, dims: Dimensions) -> list[float]:
        """The ``SolidPrimitive.dimensions`` list of validated ``dims``."""
        return [float(v) for name in self.primitive_dimensions for v in np.ravel(dims[name])]

    def from_primitive_values(self, where: str, values: Any) -> Dimensions:
        """Field values from a ``SolidPrimitive.dimensions`` list (all finite and > 0)."""
        counts = [self._dimension(name).count for name in self.primitive_dimensions]
        try:
            values = [float(v) for v in values]
        except (TypeError, ValueError):
            raise InvalidScene(f"{where}: {self.name} dimensions must be numbers, got {values!r:.60}") from None
        if len(values) != sum(counts):
            raise InvalidScene(f"{where}: a {self.name} needs {sum(counts)} dimensions, got {len(values)}")
        if not all(math.isfinite(v) and v > 0 for v in values):
            raise InvalidScene(f"{where}: {self.name} dimensions must be finite and > 0, got {str(values):.60}")
        out, start = {}, 0
        for name, count in zip(self.primitive_dimensions, counts):
            out[name] = values[start] if count == 1 else tuple(values[start : start + count])
            start += count
        return out

    def _dimension(self, name: str) -> Dimension:
        return next(d for d in self.dimensions if d.name == name)


SHAPES: dict[str, ShapeSpec] = {}


def register(spec: ShapeSpec) -> None:
    """Add (or replace) an obstacle type."""
    SHAPES[spec.name] = spec


def unregister(name: str) -> None:
    SHAPES.pop(name, None)


def shape(name: Any, where: str) -> ShapeSpec:
    """The spec of obstacle type ``name``; InvalidScene naming ``where`` and the known types."""
    spec = SHAPES.get(name) if isinstance(name, str) else None
    if spec is None:
        raise InvalidScene(f"{where}: field 'type' must be one of {tuple(SHAPES)}, got {name!r:.60}")
    return spec


def by_primitive_type(type_name: str, where: str) -> ShapeSpec:
    """The shape sent as ``SolidPrimitive`` constant ``type_name`` (e.g. "BOX", any case)."""
    wanted = str(type_name).upper()
    for spec in SHAPES.values():
        if spec.primitive_type == wanted:
            return spec
    known = [s.primitive_type for s in SHAPES.values() if s.primitive_type]
    raise InvalidScene(f"{where}: unsupported primitive type {type_name!r} (supported: {', '.join(known)})")


# ------------------------------------------------------------------ validation --
def numbers(where: str, field_name: str, value: Any, count: int) -> np.ndarray:
    """``count`` finite numbers from ``value``; InvalidScene naming ``where`` and the field otherwise."""
    plain = [value] if type(value) in (float, int) else value  # plain Python numbers: no numpy round trip
    if type(plain) in (list, tuple) and len(plain) == count and all(type(v) in (float, int) for v in plain):
        if not all(math.isfinite(v) for v in plain):
            raise InvalidScene(f"{where}: field '{field_name}' contains NaN or inf: {value!r}")
        return np.array(plain, dtype=float)
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidScene(f"{where}: field '{field_name}' must be {count} numbers, got {value!r:.60}") from None
    if arr.size != count:
        raise InvalidScene(f"{where}: field '{field_name}' must have {count} numbers, got {arr.size}")
    if not np.isfinite(arr).all():
        raise InvalidScene(f"{where}: field '{field_name}' contains NaN or inf: {value!r}")
    return arr


def validate(spec: ShapeSpec, where: str, values: Mapping[str, Any]) -> Dimensions:
    """Checked field values of a ``spec`` obstacle (defaults filled in); unknown fields are rejected."""
    unknown = sorted(set(values) - set(spec.field_names))
    if unknown:
        raise InvalidScene(f"{where}: unknown field(s) {unknown} for a {spec.name} (fields: {list(spec.field_names)})")
    out: Dimensions = {}
    for dim in spec.dimensions:
        value = values.get(dim.name)
        if value is None:
            value = dim.default
        if value is None:
            raise InvalidScene(f"{where}: missing field '{dim.name}'")
        out[dim.name] = _path(where, dim.name, value) if dim.is_path else _positive(where, dim, value)
    return out


def _positive(where: str, dim: Dimension, value: Any) -> float | tuple[float, ...]:
    arr = numbers(where, dim.name, value, dim.count)
    if (arr <= 0).any() or (arr > MAX_DIMENSION).any():
        shown = arr.tolist() if dim.count > 1 else float(arr[0])
        raise InvalidScene(f"{where}: field '{dim.name}' must be > 0 and <= {MAX_DIMENSION:g}, got {str(shown):.60}")
    return float(arr[0]) if dim.count == 1 else tuple(float(v) for v in arr)


def _path(where: str, field_name: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise InvalidScene(f"{where}: field '{field_name}' must be a file name, got {value!r:.60}")
    return value


# ------------------------------------------------------------------ pictures --
def box_faces(half: np.ndarray) -> list[np.ndarray]:
    """The six faces (4 corners each) of a box of half extents ``half``, centred."""
    hx, hy, hz = np.asarray(half, dtype=float)
    corners = np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    idx = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    return [corners[list(f)] for f in idx]


def prism_faces(bottom: np.ndarray, top: np.ndarray) -> list[np.ndarray]:
    """Side quads and the two caps between two rings of points (n, 3)."""
    n = len(bottom)
    sides = [np.array([bottom[i], bottom[(i + 1) % n], top[(i + 1) % n], top[i]]) for i in range(n)]
    return [*sides, bottom, top]


def ring(radius: float, z: float, sides: int = 16) -> np.ndarray:
    """``sides`` points on a horizontal circle at height ``z``."""
    angle = 2 * np.pi * np.arange(sides) / sides
    return np.c_[radius * np.cos(angle), radius * np.sin(angle), np.full(sides, z)]


def sphere_faces(radius: float, rings: int = 6, sides: int = 12) -> list[np.ndarray]:
    """Quads of a latitude/longitude sphere."""
    lat = np.linspace(-np.pi / 2, np.pi / 2, rings + 1)
    layers = [ring(radius * np.cos(a), radius * np.sin(a), sides) for a in lat]
    return [face for lo, hi in zip(layers[:-1], layers[1:]) for face in prism_faces(lo, hi)[:-2]]


def posed(faces: list[np.ndarray], pose: np.ndarray) -> list[np.ndarray]:
    """Polygons moved from the shape frame to the scene frame by the 4x4 ``pose``."""
    pose = np.asarray(pose, dtype=float)
    return [f @ pose[:3, :3].T + pose[:3, 3] for f in faces]


# ------------------------------------------------------------------ the table --
def _kernel(kind: str, pose: np.ndarray, half, exact: bool = True) -> KernelPrimitive:
    pose = np.asarray(pose, dtype=float)
    return KernelPrimitive(kind, pose[:3, 3].copy(), pose[:3, :3].copy(), np.asarray(half, dtype=float), exact)


def mesh_bounding_box(path: str, scale) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half extents (in the mesh frame) of a mesh file's scaled vertices."""
    vertices = np.asarray(_load_mesh(path, scale).vertices(), dtype=float)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    return 0.5 * (lo + hi), 0.5 * (hi - lo)


def _load_mesh(path: str, scale) -> coal.BVHModelBase:
    return coal.MeshLoader().load(str(path), np.asarray(scale, dtype=float))


def _mesh_kernel(d: Dimensions, pose: np.ndarray) -> KernelPrimitive:
    """The mesh's oriented bounding box: it bounds the mesh, so a touch is left to the exact model."""
    center, half = mesh_bounding_box(d["path"], d["scale"])
    box_pose = np.asarray(pose, dtype=float).copy()
    box_pose[:3, 3] = pose[:3, :3] @ center + pose[:3, 3]
    return _kernel("box", box_pose, half, exact=False)


def _mesh_faces(d: Dimensions) -> list[np.ndarray]:
    center, half = mesh_bounding_box(d["path"], d["scale"])
    return [f + center for f in box_faces(half)]


BOX = ShapeSpec(
    name="box",
    dimensions=(Dimension("size", 3),),  # full side lengths
    geometry=lambda d: coal.Box(*d["size"]),
    kernel_primitive=lambda d, pose: _kernel("box", pose, 0.5 * np.asarray(d["size"])),
    faces=lambda d: box_faces(0.5 * np.asarray(d["size"])),
    marker=lambda d: MarkerShape("CUBE", d["size"]),
    primitive_type="BOX",
    primitive_dimensions=("size",),
)
SPHERE = ShapeSpec(
    name="sphere",
    dimensions=(Dimension("radius"),),
    geometry=lambda d: coal.Sphere(d["radius"]),
    kernel_primitive=lambda d, pose: _kernel("sphere", pose, np.full(3, d["radius"])),
    faces=lambda d: sphere_faces(d["radius"]),
    marker=lambda d: MarkerShape("SPHERE", (2 * d["radius"],) * 3),
    primitive_type="SPHERE",
    primitive_dimensions=("radius",),
)
CYLINDER = ShapeSpec(
    name="cylinder",
    dimensions=(Dimension("radius"), Dimension("length")),
    geometry=lambda d: coal.Cylinder(d["radius"], d["length"]),
    kernel_primitive=lambda d, pose: _kernel("cylinder", pose, (d["radius"], d["radius"], 0.5 * d["length"])),
    faces=lambda d: prism_faces(ring(d["radius"], -0.5 * d["length"]), ring(d["radius"], 0.5 * d["length"])),
    marker=lambda d: MarkerShape("CYLINDER", (2 * d["radius"], 2 * d["radius"], d["length"])),
    primitive_type="CYLINDER",
    primitive_dimensions=("length", "radius"),  # SolidPrimitive: CYLINDER_HEIGHT = 0, CYLINDER_RADIUS = 1
)
MESH = ShapeSpec(
    name="mesh",
    dimensions=(Dimension("path", is_path=True), Dimension("scale", 3, default=(1.0, 1.0, 1.0))),
    geometry=lambda d: _load_mesh(d["path"], d["scale"]),
    kernel_primitive=_mesh_kernel,
    faces=_mesh_faces,
    marker=lambda d: MarkerShape("MESH_RESOURCE", d["scale"], f"file://{d['path']}"),
)

for _spec in (BOX, SPHERE, CYLINDER, MESH):
    register(_spec)
