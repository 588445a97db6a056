"""Collision checking: CollisionChecker (Pinocchio + coal). ``spheres`` adds a fast sphere model."""

from maru_planner.collision.checker import CollisionChecker, obstacle_geometry, self_collision_pairs

__all__ = ["CollisionChecker", "obstacle_geometry", "self_collision_pairs"]
