"""Which collision checker a planner plans on, and the exact one its paths are verified on.

``make_checkers(robot, scene, model)`` is the one place that turns ``PlannerConfig.collision_model``
into checkers (used by ``MotionPlanner.from_scene``, ``maru-plan``, ``planning_node`` and the benches):

- "spheres" (the default): the batched :class:`~maru_planner.collision.SphereCollisionChecker` to plan on,
  plus an exact checker on the same scene to re-check the final path (``docs/fast_collision.md``).
- "exact": the pinocchio + coal :class:`~maru_planner.collision.CollisionChecker`; nothing to verify.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from maru_planner.collision import CollisionChecker
from maru_planner.planning.config import COLLISION_MODELS, PlannerConfig


@dataclass(frozen=True)
class Checkers:
    """``checker`` plans; ``exact`` verifies its paths (None: ``checker`` is the exact model)."""

    checker: object
    exact: object | None


def make_checkers(robot, scene=None, model: str = PlannerConfig.collision_model) -> Checkers:
    """Checkers for ``model`` ("spheres" | "exact"; default: ``PlannerConfig``'s) on ``scene`` (None = empty scene)."""
    if model == "exact":
        return Checkers(CollisionChecker(robot, scene), None)
    if model == "spheres":
        # lazy: the sphere module loads numba, which exact-only callers never need
        from maru_planner.collision.spheres import SphereCollisionChecker

        return Checkers(SphereCollisionChecker(robot, scene), CollisionChecker(robot, scene))
    raise ValueError(f"collision model must be one of {', '.join(COLLISION_MODELS)}, got {model!r}")


def default_exact_checker(robot, checker) -> CollisionChecker | None:
    """The exact checker to verify ``checker``'s paths on: one on its scene for a sphere checker, else None."""
    return CollisionChecker(robot, checker.scene) if is_sphere_checker(checker) else None


def padded_checker(robot, checker, padding: float):
    """A checker of ``checker``'s kind on its scene that reports states closer than ``padding`` (m) as colliding.

    The sphere checker's twin shares its sphere model (no refit) and inflates its spheres and its exact
    confirmation by ``padding``; the exact checker's adds ``padding`` to every pair's security margin.
    """
    if is_sphere_checker(checker):
        spheres = sys.modules["maru_planner.collision.spheres"]
        return spheres.SphereCollisionChecker(
            robot, checker.scene, padding=checker.padding + padding, confirm=checker.confirm, spheres=checker.spheres,
            use_numba=checker.use_numba, build_budget=checker.build_budget,
            grid_min_obstacles=checker.grid_min_obstacles,
        )  # fmt: skip
    return CollisionChecker(
        robot, checker.scene, padding=checker.padding + padding, broadphase=checker.broadphase,
        build_budget=checker.build_budget, pair_list_limit=checker.pair_list_limit,
    )  # fmt: skip


def is_sphere_checker(checker) -> bool:
    """True for a :class:`SphereCollisionChecker` (whose paths need verification on the exact model)."""
    # A sphere checker can only exist once its module is imported: exact-only users skip numba's import.
    spheres = sys.modules.get("maru_planner.collision.spheres")
    return spheres is not None and isinstance(checker, spheres.SphereCollisionChecker)


def collision_model_of(checker) -> str:
    return "spheres" if is_sphere_checker(checker) else "exact"


def is_compiled_sphere_checker(checker) -> bool:
    """True for a sphere checker with numba kernels: the compiled search and shortcuts can run on it."""
    return is_sphere_checker(checker) and bool(checker.use_numba)
