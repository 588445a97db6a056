"""Tolerances of a trajectory execution, as joint_trajectory_controller and MoveIt apply them, and result codes.

- path (per joint, position and velocity): checked every control cycle until the last point's time; a value
  of 0 is not checked (the controller's convention). A violation aborts: ``PATH_TOLERANCE_VIOLATED``.
- goal (per joint, position and velocity): after the last point's time the goal is reached when every joint
  is within them; ``goal_time`` seconds later without that, ``GOAL_TOLERANCE_VIOLATED`` (0: wait forever, as
  the controller does). The default is MoveIt's execution-duration monitor: ``0.2 T + 0.5 s`` past a
  trajectory of duration ``T`` (``allowed_execution_duration_scaling`` 1.2, ``allowed_goal_duration_margin`` 0.5).
- start: MoveIt's ``allowed_start_tolerance`` (0.01 rad): the first point is refused when it is farther
  than that from the arm's current state (:class:`StartToleranceViolated`).

Codes: control_msgs/FollowJointTrajectory's result codes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from maru_planner.errors import InvalidRequest, InvalidState

PerJoint = float | Sequence[float] | np.ndarray  # one value for every joint, or one per joint
START_TOLERANCE = 0.01  # rad: MoveIt's allowed_start_tolerance
DURATION_SCALING = 1.2  # MoveIt's allowed_execution_duration_scaling
DURATION_MARGIN = 0.5  # s: MoveIt's allowed_goal_duration_margin
PATH_POSITION = 0.05  # rad: default path tolerance (the tracking target is 0.02)
GOAL_POSITION = 0.01  # rad
GOAL_VELOCITY = 0.01  # rad/s: the controller's stopped_velocity_tolerance


class ResultCode(IntEnum):
    """control_msgs/FollowJointTrajectory.Result ``error_code`` values."""

    SUCCESSFUL = 0
    INVALID_GOAL = -1
    INVALID_JOINTS = -2
    OLD_HEADER_TIMESTAMP = -3
    PATH_TOLERANCE_VIOLATED = -4
    GOAL_TOLERANCE_VIOLATED = -5


class StartToleranceViolated(InvalidState):
    """The trajectory's first point is farther from the arm's current state than the start tolerance."""


@dataclass(frozen=True)
class Tolerances:
    """Per-joint tolerances in the trajectory's joint order (see the module docstring)."""

    path_position: np.ndarray
    path_velocity: np.ndarray
    goal_position: np.ndarray
    goal_velocity: np.ndarray
    goal_time: float
    start: float = START_TOLERANCE


def tolerances(
    joints: int,
    duration: float,
    *,
    path_position: PerJoint = PATH_POSITION,
    path_velocity: PerJoint = 0.0,
    goal_position: PerJoint = GOAL_POSITION,
    goal_velocity: PerJoint = GOAL_VELOCITY,
    goal_time: float | None = None,
    start: float = START_TOLERANCE,
) -> Tolerances:
    """Checked tolerances for ``joints`` joints (a number applies to all); ``goal_time`` None: MoveIt's monitor."""
    values = {
        name: _per_joint(value, joints, name)
        for name, value in (
            ("path_position", path_position),
            ("path_velocity", path_velocity),
            ("goal_position", goal_position),
            ("goal_velocity", goal_velocity),
        )
    }
    if goal_time is None:
        goal_time = (DURATION_SCALING - 1.0) * duration + DURATION_MARGIN
    for name, value in (("goal_time", goal_time), ("start", start)):
        if not np.isfinite(value) or value < 0:
            raise InvalidRequest(f"tolerance {name}: must be a non-negative number, got {value!r}")
    return Tolerances(goal_time=float(goal_time), start=float(start), **values)


def _per_joint(value: PerJoint, joints: int, name: str) -> np.ndarray:
    array = np.broadcast_to(np.asarray(value, dtype=float), (joints,)) if np.ndim(value) == 0 else np.asarray(value)
    if array.shape != (joints,):
        raise InvalidRequest(f"tolerance {name}: expected {joints} values (one per joint), got {np.shape(value)}")
    if not np.all(np.isfinite(array)) or np.any(array < 0):
        raise InvalidRequest(f"tolerance {name}: values must be non-negative numbers, got {array.tolist()!r:.80}")
    return np.array(array, dtype=float)


def violated(error: np.ndarray, tolerance: np.ndarray) -> int:
    """The first joint whose ``|error|`` exceeds its (non-zero) tolerance, or -1."""
    bad = (tolerance > 0) & (np.abs(error) > tolerance)
    return int(np.argmax(bad)) if np.any(bad) else -1


def within_goal(position_error: np.ndarray, velocity_error: np.ndarray, tol: Tolerances) -> bool:
    return violated(position_error, tol.goal_position) < 0 and violated(velocity_error, tol.goal_velocity) < 0


def check_start(first: np.ndarray, current: np.ndarray, joint_names: Sequence[str], tol: Tolerances) -> None:
    """StartToleranceViolated naming the joint farthest from the first point (a tolerance of 0: not checked)."""
    gap = np.abs(np.asarray(first) - np.asarray(current))
    worst = int(np.argmax(gap))
    if tol.start > 0 and gap[worst] > tol.start:
        raise StartToleranceViolated(
            f"trajectory starts {gap[worst]:.4f} rad from the current state at joint '{joint_names[worst]}'"
            f" (start tolerance {tol.start:g})"
        )
