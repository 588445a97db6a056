"""The local planner of a repair: RRT-Connect between two waypoints of the request's group, planned like the
request was -- the compiled kernel on the sphere checker, else OMPL's RRTConnect on the exact one -- by the
same stages, in a context of its own (a padded checker, no certification: the certifier checks the result).

It plans padded by more than the margin -- half-way to the nearer end's clearance, at most twice the margin or
:data:`REPAIR_MIN_PADDING` if more: its checks are of states, certification's of the motion between them -- at
``config.resolution`` or :data:`REPAIR_RESOLUTION` if finer (a coarse search's gaps are what certification
caught), with a short simplification.
"""

from __future__ import annotations

import dataclasses
import itertools
import time

import numpy as np

from maru_planner.monitor import PlanMonitor
from maru_planner.planning.checkers import is_sphere_checker, padded_checker
from maru_planner.planning.context import PlanningContext
from maru_planner.planning.pipeline import Pipeline
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.space import full_configurations
from maru_planner.planning.stages.parameterize import parameterize
from maru_planner.planning.stages.search import search
from maru_planner.planning.stages.simplify import simplify
from maru_planner.planning.stages.verify import verify
from maru_planner.planning.types import MotionRequest

REPAIR_RESOLUTION = 0.02  # rad: the coarsest motion step of a repair's local search
REPAIR_SHORTCUT_TRIES = 10  # a repair's local path is short: few failed shortcuts end its simplification
REPAIR_MIN_PADDING = 0.005  # m: the most a repair may pad when twice the margin is less (a margin of 0 included)
COMPILED_PLANNER, OMPL_PLANNER = "CompiledRRTConnect", "RRTConnect"  # the local planner on spheres / exact
VERIFIED = Pipeline([search, simplify, parameterize], [verify])  # a sphere checker's paths, on the exact one
UNCHECKED = Pipeline([search, simplify, parameterize])  # the exact checker's (the certifier checks the result)


class RepairPlanner:
    """``plan_between(qa, qb, margin, deadline)`` -> full configurations qa..qb, or None (module doc)."""

    def __init__(self, problem: PlanningProblem, seed: int):
        context = problem.context
        self.robot, self.checker, self.certifier = context.robot, context.checker, context.certifier
        self.config = dataclasses.replace(  # built per repair: checking a config costs more than most requests need
            context.config,
            resolution=min(context.config.resolution, REPAIR_RESOLUTION),
            simplify_max_tries=min(context.config.simplify_max_tries, REPAIR_SHORTCUT_TRIES),
            certify=False,
            time_parameterization="trapezoid",
        )
        self.group, self.seed, self.monitor = problem.request.group, seed, problem.monitor
        self.attempt = itertools.count(1)

    def __call__(self, qa: np.ndarray, qb: np.ndarray, margin: float, deadline: float) -> np.ndarray | None:
        ends = min(self.certifier.clearance(qa), self.certifier.clearance(qb))
        padding = min(max(2.0 * margin, REPAIR_MIN_PADDING), 0.5 * (margin + ends)) if ends > margin else margin
        fast = is_sphere_checker(self.checker)
        checker = padded_checker(self.robot, self.checker if fast else self.certifier.checker, padding)
        context = PlanningContext.default(self.robot, checker, self.config)
        names = self.robot.joint_names
        indices = sorted(self.robot.group_joint_indices(self.group))
        sub = MotionRequest(
            self.group, start=dict(zip(names, qa, strict=True)),
            goal_joints={names[i]: float(qb[i]) for i in indices},
            planner_id=COMPILED_PLANNER if fast else OMPL_PLANNER,
            time_budget=max(deadline - time.monotonic(), 1e-3), seed=self.seed + next(self.attempt),
        )  # fmt: skip
        nested = PlanMonitor()
        with self.monitor.attach(_CancelsNested(nested)):
            pipeline = VERIFIED if context.exact_checker is not None else UNCHECKED
            found = pipeline.run(context, sub, nested, time.monotonic())
        if not found.success or found.path is None:
            return None
        start = np.clip(np.asarray(qa, dtype=float), self.robot.lower_limits, self.robot.upper_limits)
        return full_configurations(start, indices, np.asarray(found.path, dtype=float))


class _CancelsNested:
    """Attached to a request's monitor, its cancel reaches a nested plan (a repair) that reports its own stages."""

    def __init__(self, nested: PlanMonitor):
        self.nested = nested

    def terminate(self) -> None:
        self.nested.cancel()
