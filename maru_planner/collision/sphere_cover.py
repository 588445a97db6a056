"""Moved to :mod:`maru_planner.collision.certify.cover`; this path is kept for existing imports."""

from maru_planner.collision.certify.cover import (
    CLUSTER_BALLS,
    DISTANCE_TOLERANCE,
    MAX_REMEMBERED_COVERS,
    MAX_SOLID_PARTS,
    NO_COVER,
    SphereCover,
    cover_bounds_nb,
    solid_balls,
    solid_inside_spheres,
)

__all__ = [
    "CLUSTER_BALLS", "DISTANCE_TOLERANCE", "MAX_REMEMBERED_COVERS", "MAX_SOLID_PARTS", "NO_COVER", "SphereCover",
    "cover_bounds_nb", "solid_balls", "solid_inside_spheres",
]  # fmt: skip
