"""The limits a trajectory keeps, the request's scalings of them, and the names of the timing methods."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from maru_planner import errors

METHODS = ("toppra", "ruckig", "trapezoid")  # :func:`~maru_planner.trajectory.parameterize`'s methods
JERK_RAMP_TIME = 0.1  # s: default jerk limit = acceleration limit / this (full acceleration in 0.1 s)
# Slowest scaling a request may ask for (10,000x the full-speed duration); far below it the time
# parameterisations overflow (1e-300 gave NaN durations and internal errors).
MIN_SCALING = 1e-4


@dataclass(frozen=True)
class Limits:
    """Per-joint limits the trajectory must respect (already multiplied by the request's scaling)."""

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    @classmethod
    def scaled(
        cls,
        velocity_limits: Sequence[float] | np.ndarray,
        acceleration_limits: Sequence[float] | np.ndarray,
        velocity_scaling: float = 1.0,
        acceleration_scaling: float = 1.0,
        jerk_scaling: float = 1.0,
        jerk_limits: Sequence[float] | np.ndarray | None = None,
    ) -> Limits:
        """Limits × scaling; jerk limits default to :func:`default_jerk_limits` of the acceleration limits."""
        acc = np.asarray(acceleration_limits, float)
        jerk = default_jerk_limits(acc) if jerk_limits is None else np.asarray(jerk_limits, float)
        return cls(
            np.asarray(velocity_limits, float) * velocity_scaling,
            acc * acceleration_scaling,
            jerk * jerk_scaling,
        )


def check_scaling(value: object, name: str) -> float:
    """``value`` as a limit scaling; InvalidRequest naming ``name`` unless it is a number in [MIN_SCALING, 1]."""
    try:
        scaling = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise errors.InvalidRequest(f"{name} must be a number in [{MIN_SCALING:g}, 1], got {value!r:.40}") from exc
    if not (math.isfinite(scaling) and MIN_SCALING <= scaling <= 1.0):
        raise errors.InvalidRequest(f"{name} must be in [{MIN_SCALING:g}, 1], got {scaling:.3g}")
    return scaling


def check_method(method: str) -> str:
    """``method`` if it is one of :data:`METHODS`, else InvalidRequest naming them."""
    if method not in METHODS:
        raise errors.InvalidRequest(f"time_parameterization must be one of {', '.join(METHODS)}, got {method!r}")
    return method


def default_jerk_limits(acceleration_limits: Sequence[float] | np.ndarray) -> np.ndarray:
    """Jerk limits reaching the full acceleration in :data:`JERK_RAMP_TIME` (URDF has no jerk field)."""
    return np.asarray(acceleration_limits, float) / JERK_RAMP_TIME
