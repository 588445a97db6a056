"""A robot's collision geometries as the shape records of the GJK bound kernels
(:mod:`maru_planner.collision.kernels.support_bounds`): a box, sphere or cylinder as itself, a mesh as its convex hull.
"""

from __future__ import annotations

from collections.abc import Sequence

import coal
import numpy as np

from maru_planner.collision.kernels.support_bounds import BOX, CYLINDER, HULL, NO_SHAPE, SPHERE


def robot_shape_records(geometries: Sequence, hulls: dict[int, coal.ConvexBase]) -> tuple:
    """A robot's shape records for :func:`~maru_planner.collision.kernels.support_bounds.place_shape`
    (``geometries``: its Pinocchio geometry objects): per geometry its kind (a box, sphere or cylinder as itself, a
    mesh as its convex hull ``hulls[g]``, else ``NO_SHAPE``), placement in its joint's frame, size, and vertex range
    into the hull vertices (in their geometry's frame); then those vertices."""
    n = len(geometries)
    kind, size = np.full(n, NO_SHAPE, dtype=np.int64), np.zeros((n, 3))
    parts = [np.zeros((0, 3))] * n
    for g, obj in enumerate(geometries):
        shape = obj.geometry
        if g in hulls:
            kind[g], parts[g] = HULL, np.asarray(hulls[g].points(), dtype=float)
        elif isinstance(shape, coal.Box):
            kind[g], size[g] = BOX, shape.halfSide
        elif isinstance(shape, coal.Sphere):
            kind[g], size[g, 0] = SPHERE, shape.radius
        elif isinstance(shape, coal.Cylinder):
            kind[g], size[g, 0], size[g, 2] = CYLINDER, shape.radius, shape.halfLength
    rot = np.array([obj.placement.rotation for obj in geometries], dtype=float).reshape(n, 3, 3)
    pos = np.array([obj.placement.translation for obj in geometries], dtype=float).reshape(n, 3)
    start = np.cumsum([0] + [len(part) for part in parts]).astype(np.int64)
    return kind, rot, pos, size, start, np.ascontiguousarray(np.concatenate(parts).reshape(-1, 3))
