"""What every plan for one robot shares: its checkers, its certifier, the configuration and the search caches.

MoveIt's planning context: :class:`~maru_planner.planning.motion_planner.MotionPlanner` owns one and hands it to
each :class:`~maru_planner.planning.problem.PlanningProblem`; the search reuses the OMPL setups, the checkers
padded by a margin and the PRM roadmap it keeps here between requests. Not thread-safe: the facade serialises use.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from maru_planner.planning.checkers import default_exact_checker, is_sphere_checker, padded_checker
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.space import GroupSetup, GroupSpace

NEAR_END_PADDING = 0.75  # of the nearer end's clearance: the search's padding when an end is nearer than the margin
PADDED_CHECKERS = 4  # padded search checkers kept (the margin's, and a few for ends nearer than it)


class PlanningContext:
    """The robot, ``checker`` (plans), ``exact_checker`` (verifies; None: ``checker`` is exact), ``certifier``."""

    def __init__(self, robot: Any, checker: Any, config: PlannerConfig, exact_checker: Any = None):
        self.robot, self.checker, self.config = robot, checker, config
        self.exact_checker = exact_checker
        self.certifier = make_certifier(robot, checker, exact_checker, config)
        self.setups: dict[tuple, GroupSetup] = {}  # per (group's joint indices, checker), reused across requests
        self.padded: dict[float, Any] = {}  # padding -> the checker padded by it, oldest first
        self.roadmaps: dict[tuple, Any] = {}  # one PRM roadmap at a time (planning/planners/roadmap.py)
        self.scene: Any = None  # the scene last given (set_scene); the checkers hold it too
        self.scene_epoch = 0
        self.last_revalidation: Any = None  # the last stale roadmap's re-validation report
        self.last_search_checker: Any = checker  # the checker the last search planned on

    @classmethod
    def default(cls, robot: Any, checker: Any, config: PlannerConfig) -> PlanningContext:
        """A context verifying ``checker``'s paths on the exact checker its kind needs."""
        return cls(robot, checker, config, default_exact_checker(robot, checker))

    def set_scene(self, scene: Any) -> None:
        """Give every checker ``scene``; the certifier re-reads it and cached roadmaps become stale."""
        self.checker.set_scene(scene)
        if self.exact_checker is not None:
            self.exact_checker.set_scene(scene)
        for padded in self.padded.values():
            padded.set_scene(scene)
        self.scene = scene
        self.scene_changed()

    def scene_changed(self) -> None:
        if self.certifier is not None:
            self.certifier.prepare()
        self.scene_epoch += 1

    def scene_key(self) -> tuple:
        """Changes whenever the scene does: a set_scene call or an edit that bumps ``scene.version``."""
        scene = getattr(self.checker, "scene", None) or self.scene
        return (self.scene_epoch, id(scene), getattr(scene, "version", None))

    def search_checker(self, margin: float, start_full: np.ndarray, goal_full: np.ndarray) -> Any:
        """The checker a search whose path is certified with ``margin`` plans on (docs/certification.md, "Why the
        search is padded"): ``checker`` padded by the margin; by :data:`NEAR_END_PADDING` of the nearer end's
        clearance when an end is closer than the margin (certification keeps half of it); unpadded if it touches."""
        if self.certifier is None or margin <= 0.0:
            return self.checker
        padded = self.padded_checker(margin)
        if padded.is_valid(start_full) and padded.is_valid(goal_full):
            return padded
        ends = min(self.certifier.clearance(start_full), self.certifier.clearance(goal_full))
        return self.padded_checker(NEAR_END_PADDING * ends) if ends > 0.0 else self.checker

    def padded_checker(self, padding: float) -> Any:
        """``checker`` padded by ``padding`` (kept for the next requests, with their OMPL setups)."""
        padded = self.padded.pop(padding, None) or padded_checker(self.robot, self.checker, padding)
        self.padded[padding] = padded  # most recent last
        while len(self.padded) > PADDED_CHECKERS:
            dropped = self.padded.pop(next(iter(self.padded)))
            self.setups = {key: setup for key, setup in self.setups.items() if key[1] != id(dropped)}
        return padded

    def group_setup(self, checker: Any, names: list[str], indices: list[int], base: np.ndarray,
                    resolution: float) -> GroupSetup:  # fmt: skip
        """The group's space and OMPL setup on ``checker`` (built once), prepared for ``base`` and ``resolution``."""
        key = (tuple(indices), id(checker))
        setup = self.setups.get(key)
        if setup is None:
            lower, upper = self.robot.lower_limits[indices], self.robot.upper_limits[indices]
            setup = GroupSetup(GroupSpace(names, indices, lower, upper, base), checker, resolution)
            self.setups[key] = setup
        setup.prepare(base, resolution)
        return setup


def make_certifier(robot: Any, checker: Any, exact_checker: Any, config: PlannerConfig) -> Any:
    """A PathCertifier on the exact model, or None (certification off, or no pinocchio geometry to prove on)."""
    exact = exact_checker or checker
    if not config.certify or not hasattr(type(exact), "reachable_obstacles"):
        return None
    # lazy: certification loads numba (batched kinematics); planners on toy checkers never need it
    from maru_planner.collision.certify import PathCertifier

    spheres = checker.spheres if is_sphere_checker(checker) else None  # bounds meshes too
    return PathCertifier(robot, exact, config.safety_margin, spheres=spheres)
