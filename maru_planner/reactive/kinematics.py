"""Differential-drive base kinematics of paper 001 (eq. 1-9).

Pure rolling, no slipping. Wheel radius ``r``, half axle ``l``::

    x' = (r/2)(q_r' + q_l') cos(theta)      u = (v_R + v_L) / 2
    y' = (r/2)(q_r' + q_l') sin(theta)      w = (v_R - v_L) / (2 l)
    theta' = (r / 2l)(q_r' - q_l')          v_R = r q_r',  v_L = r q_l'
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maru_planner.reactive.description import BODY_RADIUS, HALF_AXLE, WHEEL_RADIUS


@dataclass(frozen=True)
class DiffDriveParams:
    """Geometry and limits of a two-wheel differential-drive base (SI units); defaults: urdf/mobile_manipulator."""

    wheel_radius: float = WHEEL_RADIUS
    half_axle: float = HALF_AXLE
    body_radius: float = BODY_RADIUS
    max_linear: float = 0.5
    max_angular: float = 1.0

    def __post_init__(self):
        for name in ("wheel_radius", "half_axle", "body_radius", "max_linear", "max_angular"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0.0:
                raise ValueError(f"DiffDriveParams.{name} must be a positive finite number, got {value!r}")


def wheel_speeds(v: float, w: float, params: DiffDriveParams) -> tuple[float, float]:
    """Wheel angular rates (q_r', q_l') in rad/s producing body twist (v, w) (inverse of eq. 7-8)."""
    v_right = v + w * params.half_axle
    v_left = v - w * params.half_axle
    return v_right / params.wheel_radius, v_left / params.wheel_radius


def body_velocity(q_r_dot: float, q_l_dot: float, params: DiffDriveParams) -> tuple[float, float]:
    """Body twist (u, w) from wheel rates: u = r(q_r'+q_l')/2, w = r(q_r'-q_l')/(2l)."""
    r = params.wheel_radius
    u = 0.5 * r * (q_r_dot + q_l_dot)
    w = r * (q_r_dot - q_l_dot) / (2.0 * params.half_axle)
    return u, w


def pose_rate(pose, q_r_dot: float, q_l_dot: float, params: DiffDriveParams) -> np.ndarray:
    """World-frame pose derivative (x', y', theta') from wheel rates (eq. 1-3)."""
    u, w = body_velocity(q_r_dot, q_l_dot, params)
    theta = pose[2]
    return np.array([u * math.cos(theta), u * math.sin(theta), w])


def integrate_unicycle(pose, v: float, w: float, dt: float) -> tuple[float, float, float]:
    """Pose after driving with constant (v, w) for ``dt`` seconds (exact arc integration)."""
    x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
    if abs(w) < 1e-9:
        return x + v * dt * math.cos(theta), y + v * dt * math.sin(theta), wrap_angle(theta)
    new_theta = theta + w * dt
    radius = v / w
    x += radius * (math.sin(new_theta) - math.sin(theta))
    y -= radius * (math.cos(new_theta) - math.cos(theta))
    return x, y, wrap_angle(new_theta)


def wrap_angle(angle: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def clamp_twist(v: float, w: float, max_linear: float, max_angular: float) -> tuple[float, float]:
    """Scale (v, w) down uniformly so both lie within their limits (keeps the path curvature)."""
    scale = 1.0
    if abs(v) > max_linear:
        scale = min(scale, max_linear / abs(v))
    if abs(w) > max_angular:
        scale = min(scale, max_angular / abs(w))
    return v * scale, w * scale
