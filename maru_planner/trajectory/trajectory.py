"""A time-parameterised joint trajectory: what :func:`~maru_planner.trajectory.parameterize` returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Trajectory:
    """Time-parameterised joint trajectory; rows are samples, columns follow ``joint_names``."""

    joint_names: list[str]
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0

    def to_dict(self) -> dict:
        return {
            "joint_names": list(self.joint_names),
            "times": self.times.tolist(),
            "positions": self.positions.tolist(),
            "velocities": self.velocities.tolist(),
            "accelerations": self.accelerations.tolist(),
        }
