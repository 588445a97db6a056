"""What the planning runtime runs on a worker: each function takes the worker's :class:`WorkerContext` first.

A plan goes to the worker processes when there are some, else to the thread's own planner; IK, FK, validity
checks and Cartesian paths use the thread's planner (its robot carries the attached objects, its checker
checks them).
"""

from __future__ import annotations

import dataclasses
import math
from concurrent.futures import Future
from dataclasses import dataclass

import numpy as np

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult
from maru_planner.planning.constraints import PathConstraints
from maru_planner.planning.queries import StateValidity, check_state_validity, compute_fk
from maru_planner.planning.types import MotionRequest, MotionResult
from maru_planner.robot.ik import solve_ik
from maru_planner.runtime.admission import WorkerContext, time_left
from maru_planner.runtime.robot_state import configuration


@dataclass(frozen=True)
class IkRequest:
    """Joint values of ``group`` putting each link of ``targets`` at its 4x4 pose (planning frame).

    ``seed`` starts the search (every name must be a robot joint when ``strict_seed``); ``timeout`` s from
    the call (:func:`ik_timeout`); ``avoid_collisions``: only a collision-free solution counts.
    """

    group: str
    targets: dict[str, np.ndarray]
    seed: dict[str, float]
    timeout: float
    strict_seed: bool = True
    avoid_collisions: bool = False


def ik_timeout(value: float, default: float, maximum: float) -> float:
    """An IK request's budget: <= 0 is ``default`` (the node's ik_timeout); NaN, inf or past ``maximum``
    (max_planning_time) is refused."""
    if value <= 0.0:
        return default
    if not (math.isfinite(value) and value <= maximum):
        raise errors.InvalidRequest(
            f"timeout must be finite and <= max_planning_time {maximum} s (<= 0: ik_timeout), got {value:.3g}"
        )
    return float(value)


def plan_in_context(
    context: WorkerContext, request: MotionRequest, deadline: float, monitor: PlanMonitor | None
) -> MotionResult | Future[MotionResult]:
    """The thread's plan, or the Future of a worker process's (its pool's reader thread completes it: the caller
    hears of the result one thread hand-off sooner than through this thread)."""
    request = dataclasses.replace(request, time_budget=time_left(deadline, "allowed_planning_time"))
    if context.processes is not None:
        return context.processes.submit(request, monitor)
    return context.planner.plan(request, monitor)


def ik_in_context(context: WorkerContext, request: IkRequest, deadline: float) -> np.ndarray:
    time_left(deadline, "IK timeout")
    robot = context.planner.robot  # with the attached objects (their checker checks them)
    q_seed = configuration(robot, request.seed, strict=request.strict_seed)
    is_valid = context.planner.checker.is_valid if request.avoid_collisions else None
    return solve_ik(robot, request.targets, q_seed, request.group, deadline=deadline, is_valid=is_valid)


def fk_in_context(context: WorkerContext, values: dict[str, float], links: list[str]) -> dict[str, np.ndarray]:
    robot = context.planner.robot
    return compute_fk(robot, configuration(robot, values, strict=True), links)


def validity_in_context(context: WorkerContext, values: dict[str, float], constraints: PathConstraints
                        ) -> StateValidity:  # fmt: skip
    planner = context.planner
    constraints.check_links(planner.robot)
    q = configuration(planner.robot, values, strict=True)
    return check_state_validity(planner.robot, planner.exact_checker or planner.checker, q, constraints)


def cartesian_in_context(context: WorkerContext, request: CartesianRequest) -> CartesianResult:
    return context.planner.cartesian_path(request)
