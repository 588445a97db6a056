"""Joint trajectories interpolated exactly as ros2_control's joint_trajectory_controller does (its ``spline``).

Each segment between two points is a polynomial in the time since its first point, chosen by what *both*
points carry (``Trajectory::interpolate_between_points``):

- positions only: linear, ``p(t) = p0 + (p1 - p0) t / T`` (velocity constant, acceleration 0);
- positions and velocities: cubic through both positions and velocities;
- positions, velocities and accelerations: quintic through all three.

Before the first point (when its ``time_from_start`` is > 0) the segment starts from the state the arm had
when the trajectory arrived (the controller's ``state_before_traj_msg``), at time 0. After the last point the
last point is held (its velocities and accelerations, or zeros when it carries none).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from maru_planner.errors import InvalidJointCount, InvalidJointNames, InvalidRequest, InvalidState, TooLarge

MAX_POINTS = 1_000_000  # a trajectory message's points (a 1 kHz, 15-minute trajectory)
MAX_JOINTS = 256


@dataclass(frozen=True)
class TrajectoryPoints:
    """``trajectory_msgs/JointTrajectory`` without ROS: ``times`` are ``time_from_start`` (s), one row per point.

    ``velocities`` / ``accelerations``: ``None`` when no point carries them, else ``(n, k)`` arrays whose rows
    are NaN for the points that do not (a message may carry them on some points only).
    """

    joint_names: list[str]
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None = None
    accelerations: np.ndarray | None = None

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def has_velocities(self) -> np.ndarray:
        """Per point: does it carry velocities?"""
        return _rows_present(self.velocities, len(self.times))

    def has_accelerations(self) -> np.ndarray:
        return _rows_present(self.accelerations, len(self.times))


def _rows_present(values: np.ndarray | None, n: int) -> np.ndarray:
    if values is None:
        return np.zeros(n, dtype=bool)
    return np.asarray(~np.any(np.isnan(values), axis=1), dtype=bool)


def checked_points(
    joint_names: Sequence[str],
    times: Sequence[float] | np.ndarray,
    positions: Sequence[Sequence[float]] | np.ndarray,
    velocities: Sequence[Sequence[float]] | np.ndarray | None = None,
    accelerations: Sequence[Sequence[float]] | np.ndarray | None = None,
) -> TrajectoryPoints:
    """The points as :class:`TrajectoryPoints`, or a typed error with a one-line message.

    InvalidJointNames (empty, repeated or non-string names), InvalidJointCount (a row of the wrong length),
    InvalidRequest (no points, times not strictly increasing or negative, accelerations without velocities),
    InvalidState (NaN or infinite values; a missing row of velocities/accelerations is given as NaN), TooLarge.
    """
    names = list(joint_names)
    if not names or not all(isinstance(n, str) and n for n in names):
        raise InvalidJointNames(f"trajectory joint names must be non-empty strings, got {names[:5]!r:.120}")
    if len(set(names)) != len(names):
        raise InvalidJointNames(f"trajectory joint names repeat: {names[:10]!r:.120}")
    if len(names) > MAX_JOINTS:
        raise TooLarge(f"trajectory has {len(names)} joints, more than {MAX_JOINTS}")
    t = _array(times, "times", 1)
    if len(t) == 0:
        raise InvalidRequest("trajectory has no points")
    if len(t) > MAX_POINTS:
        raise TooLarge(f"trajectory has {len(t)} points, more than {MAX_POINTS}")
    if not np.all(np.isfinite(t)):
        raise InvalidState(f"trajectory point {int(np.argmin(np.isfinite(t)))}: time_from_start is NaN or infinite")
    if t[0] < 0:
        raise InvalidRequest(f"trajectory point 0: time_from_start {t[0]:g} s is negative")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise InvalidRequest(
            f"trajectory point {i}: time_from_start {t[i]:g} s does not increase (previous {t[i - 1]:g})"
        )
    p = _rows(positions, "positions", len(t), len(names), optional_rows=False)
    v = None if velocities is None else _rows(velocities, "velocities", len(t), len(names), optional_rows=True)
    a = None if accelerations is None else _rows(accelerations, "accelerations", len(t), len(names), optional_rows=True)
    points = TrajectoryPoints(names, t, p, v, a)
    without_velocity = points.has_accelerations() & ~points.has_velocities()
    if np.any(without_velocity):
        raise InvalidRequest(f"trajectory point {int(np.argmax(without_velocity))}: accelerations without velocities")
    return points


def _array(values: object, what: str, ndim: int) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InvalidRequest(f"trajectory {what}: not numbers ({type(values).__name__})") from None
    if array.ndim != ndim:
        raise InvalidJointCount(f"trajectory {what}: expected {ndim} dimension(s), got shape {array.shape}")
    return array


def _rows(values: object, what: str, n: int, k: int, *, optional_rows: bool) -> np.ndarray:
    """An ``(n, k)`` array; with ``optional_rows`` a row may be all NaN (absent), never partly NaN."""
    array = _array(values, what, 2)
    if array.shape != (n, k):
        raise InvalidJointCount(f"trajectory {what}: expected {n} points x {k} joints, got shape {array.shape}")
    bad = ~np.isfinite(array)
    if optional_rows:
        bad &= ~np.all(np.isnan(array), axis=1, keepdims=True)
    if np.any(bad):
        i, j = np.argwhere(bad)[0]
        raise InvalidState(f"trajectory point {i}: {what} of joint {j} is NaN or infinite")
    return array


@dataclass(frozen=True)
class Sample:
    """Desired positions, velocities and accelerations at ``times`` (rows)."""

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray


class SplineTrajectory:
    """The controller's piecewise polynomial through ``points``, starting from ``before`` at time 0.

    ``before``: positions (and optionally velocities, accelerations) of the arm when the trajectory
    arrived, in the points' joint order; used only before the first point's time.
    """

    def __init__(
        self,
        points: TrajectoryPoints,
        before_positions: np.ndarray,
        before_velocities: np.ndarray | None = None,
        before_accelerations: np.ndarray | None = None,
    ):
        self.points = points
        k = len(points.joint_names)
        start = np.full((3, k), np.nan)
        start[0] = before_positions
        if before_velocities is not None:
            start[1] = before_velocities
        if before_accelerations is not None:
            start[2] = before_accelerations
        self.knot_times = np.concatenate([[0.0], points.times]) if points.times[0] > 0 else points.times.copy()
        lead = points.times[0] > 0
        pos = _stack(start[0], points.positions, lead)
        vel = _stack(start[1], _or_nan(points.velocities, points.positions.shape), lead)
        acc = _stack(start[2], _or_nan(points.accelerations, points.positions.shape), lead)
        self._last = (pos[-1], np.nan_to_num(vel[-1]), np.nan_to_num(acc[-1]))
        self.coefficients = segment_coefficients(np.diff(self.knot_times), pos, vel, acc)

    @property
    def duration(self) -> float:
        return self.points.duration

    def sample(self, times: np.ndarray | Sequence[float]) -> Sample:
        """Desired state at each of ``times`` (s since the trajectory started)."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        k = self.points.positions.shape[1]
        positions, velocities, accelerations = (np.empty((len(t), k)) for _ in range(3))
        after = t >= self.knot_times[-1]
        positions[after], velocities[after], accelerations[after] = self._last
        inside = ~after
        if len(self.coefficients) and np.any(inside):
            segment = np.clip(
                np.searchsorted(self.knot_times, t[inside], side="right") - 1, 0, len(self.coefficients) - 1
            )
            tau = np.clip(t[inside] - self.knot_times[segment], 0.0, None)  # before time 0: the start state
            c = self.coefficients[segment]  # (m, k, 6)
            powers = tau[:, None] ** np.arange(6)[None, :]  # (m, 6)
            positions[inside] = np.einsum("mkc,mc->mk", c, powers)
            velocities[inside] = np.einsum("mkc,mc->mk", c[:, :, 1:] * np.arange(1, 6), powers[:, :5])
            accelerations[inside] = np.einsum("mkc,mc->mk", c[:, :, 2:] * np.array([2, 6, 12, 20]), powers[:, :4])
        return Sample(t, positions, velocities, accelerations)


def _or_nan(values: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
    return np.full(shape, np.nan) if values is None else values


def _stack(first: np.ndarray, rest: np.ndarray, lead: bool) -> np.ndarray:
    return np.vstack([first[None], rest]) if lead else rest


def segment_coefficients(durations: np.ndarray, pos: np.ndarray, vel: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """``(segments, joints, 6)`` polynomial coefficients (ascending powers of the time in the segment).

    A segment is quintic when both its ends carry velocities and accelerations, cubic when both carry
    velocities, else linear: the controller's ``interpolate_between_points`` formulas.
    """
    T = np.asarray(durations, dtype=float)[:, None]
    p0, p1 = pos[:-1], pos[1:]
    v0, v1 = np.nan_to_num(vel[:-1]), np.nan_to_num(vel[1:])
    a0, a1 = np.nan_to_num(acc[:-1]), np.nan_to_num(acc[1:])
    has_v = ~np.any(np.isnan(vel), axis=1)
    has_a = ~np.any(np.isnan(acc), axis=1)
    cubic = has_v[:-1] & has_v[1:]
    quintic = cubic & has_a[:-1] & has_a[1:]
    out = np.zeros((len(T), pos.shape[1], 6))
    out[:, :, 0], out[:, :, 1] = p0, (p1 - p0) / T  # linear
    out[cubic] = _cubic(T, p0, v0, p1, v1)[cubic]
    out[quintic] = _quintic(T, p0, v0, a0, p1, v1, a1)[quintic]
    return out


def _cubic(T: np.ndarray, p0: np.ndarray, v0: np.ndarray, p1: np.ndarray, v1: np.ndarray) -> np.ndarray:
    """Per segment (rows; ``T`` a column), the cubic through both ends' positions and velocities: ``(n, k, 6)``."""
    c2 = (-3.0 * p0 + 3.0 * p1 - 2.0 * v0 * T - v1 * T) / T**2
    c3 = (2.0 * p0 - 2.0 * p1 + v0 * T + v1 * T) / T**3
    zero = np.zeros_like(p0)
    return np.stack([p0, v0, c2, c3, zero, zero], axis=2)


def _quintic(
    T: np.ndarray, p0: np.ndarray, v0: np.ndarray, a0: np.ndarray, p1: np.ndarray, v1: np.ndarray, a1: np.ndarray
) -> np.ndarray:
    c3 = (-20.0 * p0 + 20.0 * p1 - 3.0 * a0 * T**2 + a1 * T**2 - 12.0 * v0 * T - 8.0 * v1 * T) / (2.0 * T**3)
    c4 = (30.0 * p0 - 30.0 * p1 + 3.0 * a0 * T**2 - 2.0 * a1 * T**2 + 16.0 * v0 * T + 14.0 * v1 * T) / (2.0 * T**4)
    c5 = (-12.0 * p0 + 12.0 * p1 - a0 * T**2 + a1 * T**2 - 6.0 * v0 * T - 6.0 * v1 * T) / (2.0 * T**5)
    return np.stack([p0, v0, 0.5 * a0, c3, c4, c5], axis=2)
