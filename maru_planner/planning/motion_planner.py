"""``MotionPlanner.plan(MotionRequest) -> MotionResult``: the facade over the planning pipeline.

A plan is a straight line of stages (:mod:`~maru_planner.planning.pipeline`): the request adapters check the
request and build a :class:`~maru_planner.planning.problem.PlanningProblem` (validation, goal or IK, path
constraints, the search's checker), then search -> simplify -> parameterize, then certify (a pinocchio robot,
``config.certify``, the default) or verify (a sphere plan without certification). A request with path
constraints takes its planner's stages: search -> simplify -> prove -> time_dense. One hard time budget covers
them all; bad input never raises: the typed error (``maru_planner.errors``) becomes ``result.status`` + message.

Watching and cancelling: ``plan(request, monitor)`` reports the stages ("validation", "ik", "search",
"simplify", "parameterize", "certify") with the tree size and best path length where they are known, attaches
every OMPL search to the :class:`~maru_planner.monitor.PlanMonitor` (``cancel()`` ends it at OMPL's next check)
and checks it between stages and in the Python loops; a cancelled plan ends with PLANNING_FAILED and a
:class:`~maru_planner.errors.PlanningCancelled` error, its statistics as far as it got.

Threads: ``plan`` and ``set_scene`` of one MotionPlanner are serialised by its own lock (the robot model,
checkers and search caches of its :class:`~maru_planner.planning.context.PlanningContext` are not thread-safe),
and every OMPL search in the process runs under one module lock (:data:`OMPL_LOCK`: OMPL's seed generator is
process-global). Concurrent requests therefore queue; parallel planning takes separate processes.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from maru_planner.monitor import PlanMonitor
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult, compute_cartesian_path
from maru_planner.planning.checkers import collision_model_of, default_exact_checker, make_checkers
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.context import NEAR_END_PADDING, PADDED_CHECKERS, PlanningContext
from maru_planner.planning.pipeline import Pipeline
from maru_planner.planning.planners.ompl_search import OMPL_LOCK, seeded_ompl
from maru_planner.planning.stages.certify import certify
from maru_planner.planning.stages.parameterize import CERTIFIED_CHORD_STEP, parameterize
from maru_planner.planning.stages.prove import prove
from maru_planner.planning.stages.repair import REPAIR_MIN_PADDING, REPAIR_RESOLUTION, REPAIR_SHORTCUT_TRIES
from maru_planner.planning.stages.search import search
from maru_planner.planning.stages.simplify import simplify
from maru_planner.planning.stages.time_dense import time_dense
from maru_planner.planning.stages.verify import verify
from maru_planner.planning.types import MotionRequest, MotionResult
from maru_planner.robot.attached import attachment_key, robot_with_attached

__all__ = [
    "CERTIFIED_CHORD_STEP",
    "NEAR_END_PADDING",
    "OMPL_LOCK",
    "PADDED_CHECKERS",
    "REPAIR_MIN_PADDING",
    "REPAIR_RESOLUTION",
    "REPAIR_SHORTCUT_TRIES",
    "MotionPlanner",
    "seeded_ompl",
]

#: The planning pipelines by what the request needs: its planner's path constraints, or the default.
CERTIFIED = Pipeline([search, simplify, parameterize], [certify])
VERIFIED = Pipeline([search, simplify, parameterize], [verify])
UNCHECKED = Pipeline([search, simplify, parameterize])
CONSTRAINED = Pipeline([search, simplify, prove, time_dense])


class MotionPlanner:
    """Arm motion planning for one robot model and collision checker (see module doc).

    With a pinocchio robot (``config.certify``, the default) every returned path is certified: proven collision-free
    on the exact model between its waypoints, keeping ``safety_margin`` (``docs/certification.md``); a failing
    segment is re-planned locally, up to ``max_refinements`` times in the time left, before the request fails.
    ``stats.certified``, ``certify_time``, ``min_clearance`` and ``repairs`` report it. Without certification, a
    plan on a :class:`~maru_planner.collision.SphereCollisionChecker` is verified on ``exact_checker`` (default: a
    :class:`~maru_planner.collision.CollisionChecker` on the same scene) and re-planned at half the motion
    resolution while it fails (``stats.verified``, ``verify_time``, ``replans``).
    """

    def __init__(self, robot: Any, checker: Any, config: PlannerConfig | None = None, scene: Any = None,
                 exact_checker: Any = None):  # fmt: skip
        config = config or PlannerConfig()
        if exact_checker is None:
            exact_checker = default_exact_checker(robot, checker)
        self.context = PlanningContext(robot, checker, config, exact_checker)
        self._lock = threading.RLock()
        if scene is not None:
            self.set_scene(scene)

    @classmethod
    def from_scene(cls, robot: Any, scene: Any = None, config: PlannerConfig | None = None) -> MotionPlanner:
        """A planner on the checker ``config.collision_model`` names ("exact" | "spheres")."""
        config = config or PlannerConfig()
        robot = robot_with_attached(robot, scene)
        checkers = make_checkers(robot, scene, config.collision_model)
        planner = cls(robot, checkers.checker, config, exact_checker=checkers.exact)
        planner.scene = scene
        return planner

    # --- what it plans with (the context's) --------------------------------------------------
    @property
    def robot(self) -> Any:
        return self.context.robot

    @property
    def checker(self) -> Any:
        return self.context.checker

    @property
    def exact_checker(self) -> Any:
        return self.context.exact_checker

    @property
    def certifier(self) -> Any:
        return self.context.certifier

    @property
    def config(self) -> PlannerConfig:
        return self.context.config

    @property
    def scene(self) -> Any:
        return self.context.scene

    @scene.setter
    def scene(self, scene: Any) -> None:
        self.context.scene = scene

    @property
    def last_revalidation(self) -> Any:
        """The last stale roadmap's re-validation report (PRM), or None."""
        return self.context.last_revalidation

    # --- scene -------------------------------------------------------------------------------
    def set_scene(self, scene: Any) -> None:
        """Give the checker(s) a new scene; cached roadmaps are re-validated at their next query.

        When the scene's attached objects differ from those the robot carries, the context (robot, checkers,
        certifier, caches) is rebuilt around them (:func:`~maru_planner.scene_attached.robot_with_attached`).
        """
        with self._lock:
            context = self.context
            if attachment_key(scene) == attachment_key(context.robot):
                context.set_scene(scene)
                return
            robot = robot_with_attached(context.robot, scene)
            checkers = make_checkers(robot, scene, collision_model_of(context.checker))
            self.context = PlanningContext(robot, checkers.checker, context.config, checkers.exact)
            self.context.scene, self.context.scene_epoch = scene, context.scene_epoch
            self.context.scene_changed()

    def _follow_attachments(self) -> None:
        """Pick up objects attached or detached by editing the scene in place since the last call."""
        scene = getattr(self.checker, "scene", None)
        if scene is not None and attachment_key(scene) != attachment_key(self.robot):
            self.set_scene(scene)

    # --- planning ----------------------------------------------------------------------------
    def plan(self, request: MotionRequest, monitor: PlanMonitor | None = None) -> MotionResult:
        """Plan ``request``; never raises (errors become the result's status and message).

        ``monitor`` receives the stages and progress and can cancel the plan from another thread (module doc).
        """
        t0 = time.monotonic()
        with self._lock:
            self._follow_attachments()
            return self._pipeline_for(request).run(self.context, request, monitor or PlanMonitor(), t0)

    def _pipeline_for(self, request: MotionRequest) -> Pipeline:
        constraints = getattr(request, "path_constraints", None)
        if constraints is not None and not constraints.empty:
            return CONSTRAINED
        if self.context.certifier is not None:
            return CERTIFIED
        return VERIFIED if self.context.exact_checker is not None else UNCHECKED

    def cartesian_path(self, request: CartesianRequest) -> CartesianResult:
        """A straight task-space path (:mod:`~maru_planner.planning.cartesian`) on this planner's robot,
        checker and certifier; never raises."""
        with self._lock:
            self._follow_attachments()
            return compute_cartesian_path(self.context, request)
