"""Checks of a :class:`~maru_planner.planning.types.MotionRequest`: its fields, its joint values, its end states.

Each failure is a typed error (``maru_planner.errors``) with a one-line message naming the first bad field.
"""

from __future__ import annotations

import math
import secrets
from collections.abc import Callable
from typing import Any

import numpy as np

from maru_planner import errors
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.types import MotionRequest
from maru_planner.trajectory import check_method, check_scaling

MAX_ATTEMPTS = 1000  # searches of one request (each within the request's budget)


def finite_time(value: Any, name: str) -> float:
    """``value`` as a finite number of seconds > 0; InvalidRequest otherwise."""
    try:
        value = float(value)
    except (TypeError, ValueError) as exc:
        raise errors.InvalidRequest(f"{name} must be a number, got {value!r}") from exc
    if not math.isfinite(value) or value <= 0:
        raise errors.InvalidRequest(f"{name} must be a finite number > 0, got {value}")
    return value


def safety_margin(request: MotionRequest, config: PlannerConfig) -> float:
    """The request's safety margin (m), else the configuration's; InvalidRequest unless finite and >= 0."""
    value: Any = config.safety_margin if getattr(request, "safety_margin", None) is None else request.safety_margin
    try:
        margin = float(value)
    except (TypeError, ValueError) as exc:
        raise errors.InvalidRequest(f"safety_margin must be a number (m), got {value!r}") from exc
    if not (math.isfinite(margin) and margin >= 0.0):
        raise errors.InvalidRequest(f"safety_margin must be a finite number >= 0 m, got {margin}")
    return margin


def check_request(request: MotionRequest, config: PlannerConfig) -> tuple[float, int]:
    """``request``'s time budget and seed (its own, or a random one); InvalidRequest naming the first bad field
    among time_budget, attempts, the scalings, time_parameterization, safety_margin and seed."""
    budget = finite_time(request.time_budget, "time_budget")
    if not 1 <= int(request.attempts) <= MAX_ATTEMPTS:
        raise errors.InvalidRequest(f"attempts must be in [1, {MAX_ATTEMPTS}], got {request.attempts}")
    for name in ("velocity_scaling", "acceleration_scaling", "jerk_scaling"):
        check_scaling(getattr(request, name), name)
    check_method(request.time_parameterization or config.time_parameterization)
    safety_margin(request, config)
    seed = int(request.seed) if request.seed is not None else secrets.randbelow(2**31 - 1)
    if not 0 <= seed < 2**63:
        raise errors.InvalidRequest(f"seed must be in [0, 2^63), got {seed}")
    return budget, seed


def check_values(robot: Any, values: Any, what: str) -> dict[int, float]:
    """Joint index -> value for a name -> value map; unknown names, non-numbers, NaN and limits raise."""
    if not isinstance(values, dict):
        raise errors.InvalidRequest(f"{what} must map joint names to values, got {type(values).__name__}")
    known = {n: i for i, n in enumerate(robot.joint_names)}
    unknown = [n for n in values if n not in known]
    if unknown:
        raise errors.InvalidJointNames(f"{what}: unknown joint(s) {', '.join(map(str, unknown))}")
    out = {}
    lower, upper = np.asarray(robot.lower_limits), np.asarray(robot.upper_limits)
    for name, value in values.items():
        i = known[name]
        try:
            v = float(value)
        except (TypeError, ValueError) as exc:
            raise errors.InvalidState(f"{what}: joint {name} has a non-numeric value {value!r}") from exc
        if not math.isfinite(v):
            raise errors.InvalidState(f"{what}: joint {name} is {v}")
        if v < lower[i] - 1e-9 or v > upper[i] + 1e-9:
            raise errors.InvalidState(
                f"{what}: joint {name} = {v:.4f} is outside its limits [{lower[i]:.4f}, {upper[i]:.4f}]"
            )
        out[i] = min(max(v, lower[i]), upper[i])
    return out


def start_configuration(robot: Any, start: dict | None, indices: Any, group: str = "") -> np.ndarray:
    """Full configuration of ``start`` ({joint: value}, checked: names, NaN, limits, every joint of
    ``indices`` given); joints it does not name are at neutral."""
    if not start:
        raise errors.NoStartState("no start state given (start is empty)")
    values = check_values(robot, start, "start")
    missing = [robot.joint_names[i] for i in indices if i not in values]
    if missing:
        raise errors.InvalidJointNames(f"start is missing joint(s) of group {group}: {', '.join(missing)}")
    q = np.asarray(robot.neutral(), dtype=float).copy()
    for i, v in values.items():
        q[i] = v
    return q


def check_free(checker: Any, q: np.ndarray, error_cls: Callable[..., Exception], what: str) -> None:
    """Raise ``error_cls`` naming the colliding pairs if the full configuration ``q`` collides on ``checker``."""
    if checker.is_valid(q):
        return
    pairs = list(checker.colliding_pairs(q))
    named = ", ".join(f"{a}–{b}" for a, b in pairs[:5]) or "unknown bodies"
    raise error_cls(f"{what} configuration is in collision: {named}", pairs=pairs)
