"""Collision checking: ``CollisionChecker`` (Pinocchio + coal, exact) and ``SphereCollisionChecker``
(batched sphere model, numba; see ``docs/fast_collision.md``), both on full robot configurations.

The sphere names are imported on first use (PEP 562), so code that only needs the exact checker does
not pay numba's import.
"""

import importlib

from maru_planner.collision.checker import CollisionChecker, self_collision_pairs

_SPHERE_NAMES = ("PathVerification", "SphereCollisionChecker", "densify", "verify_path")

__all__ = ["CollisionChecker", "self_collision_pairs", *_SPHERE_NAMES]


def __getattr__(name: str):
    if name in _SPHERE_NAMES:
        return getattr(importlib.import_module("maru_planner.collision.spheres"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
