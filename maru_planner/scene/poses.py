"""Poses of the scene: 4x4 matrices from the forms scenes and requests write, roll-pitch-yaw both ways."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from maru_planner.errors import InvalidScene
from maru_planner.scene.shapes import numbers


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) (URDF / REP 103 convention)."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a rotation matrix, the inverse of :func:`rpy_matrix` (gimbal lock: all in yaw)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-9:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


MAX_COORDINATE = 1e3  # m: |x|, |y| and |z| of an obstacle's position in the scene frame


def pose_matrix(pose: Any, where: str = "pose") -> np.ndarray:
    """A 4x4 from a 4x4, {xyz, rpy}, (x, y, z) or (x, y, z, roll, pitch, yaw); finite, its position within
    :data:`MAX_COORDINATE` (else InvalidScene naming ``where``)."""
    T = _pose_matrix(pose, where)
    if np.abs(T[:3, 3]).max() > MAX_COORDINATE:
        shown = ", ".join(f"{v:.4g}" for v in T[:3, 3])
        raise InvalidScene(f"{where}: pose position ({shown}) is farther than {MAX_COORDINATE:g} m along an axis")
    return T


def _pose_matrix(pose: Any, where: str) -> np.ndarray:
    if pose is None:
        return np.eye(4)
    if isinstance(pose, dict):
        unknown = set(pose) - {"xyz", "rpy"}
        if unknown:
            raise InvalidScene(f"{where}: unknown pose field(s) {sorted(unknown)} (use xyz, rpy)")
        T = np.eye(4)
        T[:3, 3] = numbers(where, "pose.xyz", pose.get("xyz", [0, 0, 0]), 3)
        T[:3, :3] = rpy_matrix(*numbers(where, "pose.rpy", pose.get("rpy", [0, 0, 0]), 3))
        return T
    try:
        arr = np.asarray(pose, dtype=float)
    except (TypeError, ValueError):  # e.g. a list holding text or nested lists of uneven length
        raise InvalidScene(
            f"{where}: pose must be a 4x4, {{xyz, rpy}}, xyz or xyz+rpy of numbers, got {pose!r:.80}"
        ) from None
    if arr.shape == (4, 4):
        if not np.all(np.isfinite(arr)):
            raise InvalidScene(f"{where}: pose contains NaN or inf")
        R = arr[:3, :3]
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise InvalidScene(f"{where}: pose rotation is not a rotation matrix")
        return arr.copy()
    flat = arr.reshape(-1)
    if flat.size == 3:
        T = np.eye(4)
        T[:3, 3] = numbers(where, "pose", flat, 3)
        return T
    if flat.size == 6:
        vals = numbers(where, "pose", flat, 6)
        T = np.eye(4)
        T[:3, 3], T[:3, :3] = vals[:3], rpy_matrix(*vals[3:])
        return T
    raise InvalidScene(f"{where}: pose must be a 4x4, {{xyz, rpy}}, xyz or xyz+rpy, got shape {arr.shape}")
