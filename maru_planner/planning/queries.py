"""State queries of the core, after MoveIt's ``move_group`` services (no ROS here).

- :func:`compute_fk`: link poses of a robot state (``GetPositionFK``);
- :func:`check_state_validity`: whether a state is free, which pairs collide, its clearance and
  how far it is outside optional path constraints (``GetStateValidity``);
- :func:`query_planners`: the registered planners with their parameters (defaults, ranges,
  descriptions) and capabilities (``query_planner_interface`` + ``get_planner_params``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from maru_planner import errors
from maru_planner.params import ParamSpec
from maru_planner.planning.constraints import PathConstraints
from maru_planner.planning.links import check_link, link_names
from maru_planner.planning.planners.registry import PLANNERS, ArmPlannerSpec


def compute_fk(robot, q: np.ndarray, links: Sequence[str] = ()) -> dict[str, np.ndarray]:
    """{link: 4x4 pose in the root frame} at full configuration ``q``; every link when ``links`` is empty.

    InvalidState for a value that is not finite or outside its joint's limits."""
    q = _robot_state(robot, q)
    wanted = list(links) or link_names(robot)
    ids = [check_link(robot, link) for link in wanted]
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return {link: data.oMf[fid].homogeneous.copy() for link, fid in zip(wanted, ids, strict=True)}


LIMIT_TOLERANCE = 1e-9  # rad or m a joint value may pass its limit by (rounding), as a request's start may


def _robot_state(robot, q: np.ndarray) -> np.ndarray:
    """``q`` as a float array; InvalidState unless it is ``robot.nq`` finite values within the joint limits."""
    q = np.asarray(q, dtype=float)
    if q.shape != (robot.nq,):
        raise errors.InvalidState(f"robot state must be {robot.nq} finite values, got shape {q.shape}")
    lower, upper = np.asarray(robot.lower_limits), np.asarray(robot.upper_limits)
    # NaN compares False: not-finite values are caught by the isfinite test, not by the limits
    outside = ~np.isfinite(q) | (q < lower - LIMIT_TOLERANCE) | (q > upper + LIMIT_TOLERANCE)
    if outside.any():
        k = int(np.flatnonzero(outside)[0])
        name = robot.joint_names[k] if k < len(robot.joint_names) else f"q[{k}]"
        raise errors.InvalidState(
            f"robot state: joint {name} = {q[k]:.4g} is "
            + (f"outside its limits [{lower[k]:.4f}, {upper[k]:.4f}]" if np.isfinite(q[k]) else "not finite")
        )
    return q


@dataclass
class StateValidity:
    """Answer of :func:`check_state_validity` (distances in m, angles in rad)."""

    valid: bool
    colliding_pairs: list[tuple[str, str]] = field(default_factory=list)
    clearance: float = math.inf  # smallest distance over the checked pairs; <= 0 in collision
    closest_pair: tuple[str, str] = ("", "")
    within_limits: bool = True
    orientation_violation: float = 0.0
    position_violation: float = 0.0


def check_state_validity(robot, checker, q: np.ndarray, constraints: PathConstraints | None = None) -> StateValidity:
    """Collisions (self, scene, attached objects) and ``constraints`` at full configuration ``q``.

    A value that is not finite or outside its joint's limits is no state to judge: InvalidState names the joint.
    """
    q = _robot_state(robot, q)
    pairs = list(checker.colliding_pairs(q))
    closest, distance = checker.closest_pair(q)
    within = robot.within_limits(q)
    answer = StateValidity(
        valid=not pairs and within,
        colliding_pairs=pairs,
        clearance=float(distance) - float(getattr(checker, "padding", 0.0)),
        closest_pair=tuple(closest),
        within_limits=within,
    )
    if constraints is not None and not constraints.empty:
        orientation, position = constraints.violation(robot, q)
        answer.orientation_violation, answer.position_violation = orientation, position
        answer.valid = answer.valid and orientation <= 0.0 and position <= 0.0
    return answer


@dataclass(frozen=True)
class PlannerParameter:
    """One parameter of a planner: its declaration and the value in use."""

    spec: ParamSpec
    current: Any

    def as_dict(self) -> dict[str, Any]:
        spec = self.spec
        return {
            "name": spec.name,
            "type": getattr(spec.value_type, "__name__", str(spec.value_type)),
            "default": spec.default,
            "current": self.current,
            "lower": -math.inf if spec.lower is None else spec.lower,
            "upper": math.inf if spec.upper is None else spec.upper,
            "choices": list(spec.choices or ()),
            "description": spec.description,
        }


@dataclass(frozen=True)
class PlannerDescription:
    """A registered planner as :func:`query_planners` reports it."""

    id: str
    description: str
    capabilities: tuple[str, ...]
    parameters: tuple[PlannerParameter, ...]

    def as_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "description": self.description,
            "capabilities": list(self.capabilities),
            "parameters": [p.as_dict() for p in self.parameters],
        }


def query_planners(overrides: Mapping[str, Mapping[str, Any]] | None = None) -> list[PlannerDescription]:
    """Every registered planner, its parameters' current values from ``overrides`` ({id: {name: value}})."""
    overrides = overrides or {}
    return [_describe(spec, overrides.get(spec.id, {})) for spec in PLANNERS.values()]


def _describe(spec: ArmPlannerSpec, values: Mapping[str, Any]) -> PlannerDescription:
    parameters = tuple(PlannerParameter(p, values.get(name, p.default)) for name, p in spec.params.items())
    return PlannerDescription(spec.id, spec.description, tuple(sorted(spec.capabilities)), parameters)
