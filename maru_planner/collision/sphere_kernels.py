"""Moved to :mod:`maru_planner.collision.kernels` (:mod:`~maru_planner.collision.kernels.primitives`,
:mod:`~maru_planner.collision.kernels.packing`, :mod:`~maru_planner.collision.kernels.grid`,
:mod:`~maru_planner.collision.kernels.sphere_scan`); this path is kept for existing imports."""

from maru_planner.collision.kernels.grid import NO_GRID, build_grid, unpack_grid
from maru_planner.collision.kernels.packing import pack_robot, pack_scene, unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import (
    AMBIGUOUS,
    COLLIDING,
    VALID,
    box_distance,
    cylinder_distance,
    obstacle_distance,
    point_obstacle_distance,
)
from maru_planner.collision.kernels.sphere_scan import classify_state, scan_nb, sphere_obstacle_distances_nb

__all__ = [
    "AMBIGUOUS", "COLLIDING", "NO_GRID", "VALID", "box_distance", "build_grid", "classify_state", "cylinder_distance",
    "obstacle_distance", "pack_robot", "pack_scene", "point_obstacle_distance", "scan_nb",
    "sphere_obstacle_distances_nb", "unpack_grid", "unpack_robot", "unpack_scene",
]  # fmt: skip
