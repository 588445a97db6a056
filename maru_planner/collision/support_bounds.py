"""Moved: the GJK bound kernels to :mod:`maru_planner.collision.kernels.support_bounds`, a robot's shape records to
:mod:`maru_planner.collision.shape_records`; this path is kept for existing imports."""

from maru_planner.collision.kernels.support_bounds import (
    BOX,
    CYLINDER,
    GJK_ITERATIONS,
    GJK_RELATIVE_TOLERANCE,
    GJK_TOLERANCE,
    HULL,
    NO_SHAPE,
    SPHERE,
    convex_bound,
    load_primitive,
    new_records,
    place_shape,
)
from maru_planner.collision.shape_records import robot_shape_records

__all__ = [
    "BOX", "CYLINDER", "GJK_ITERATIONS", "GJK_RELATIVE_TOLERANCE", "GJK_TOLERANCE", "HULL", "NO_SHAPE", "SPHERE",
    "convex_bound", "load_primitive", "new_records", "place_shape", "robot_shape_records",
]  # fmt: skip
