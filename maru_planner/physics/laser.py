"""A 2-D laser like the challenge's Hokuyo UST-10, ray-cast with MuJoCo's ``mj_multiRay``.

720 beams over 270 deg (-2.35619 .. 2.35619 rad, Gazebo's spacing: (max - min) / (samples - 1)),
0.1 .. 30 m, 50 Hz, Gaussian noise sd 1 mm. Mount: the challenge runs with
``JACKAL_LASER_OFFSET="-0.065 0 0.01"`` on the Jackal's front mount (0.12 m ahead of the centre), so
the laser sits 0.055 m ahead of base_link; its beams are horizontal at ``height`` above the floor.
Only obstacle geoms (their MJCF group) are seen, so neither the robot nor the floor returns.
A beam with no return reads +inf (REP 117).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np


@dataclass(frozen=True)
class LaserSpec:
    beams: int = 720
    angle_min: float = -2.35619
    angle_max: float = 2.35619
    range_min: float = 0.1
    range_max: float = 30.0
    rate: float = 50.0  # Hz
    noise: float = 0.001  # m, sd
    x: float = 0.055  # m in base_link (front mount 0.12 + offset -0.065)
    y: float = 0.0
    height: float = 0.25  # m above the floor

    @property
    def angle_increment(self) -> float:
        return (self.angle_max - self.angle_min) / (self.beams - 1)

    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.beams)


@dataclass
class Scan:
    """One scan in the laser frame (fields as sensor_msgs/LaserScan); ``stamp`` is sim time (s)."""

    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    stamp: float


class Laser:
    """Casts the spec's beams from the laser's pose in the world; seeded noise."""

    def __init__(self, spec: LaserSpec, group: int, rng: np.random.Generator):
        self.spec = spec
        self.rng = rng
        self._angles = spec.angles()
        self._groups = np.zeros(6, dtype=np.uint8)
        self._groups[group] = 1
        self._geomid = np.zeros(spec.beams, dtype=np.int32)
        self._dist = np.zeros(spec.beams, dtype=np.float64)
        self._vec = np.zeros((spec.beams, 3))  # beam directions, reused (the z column stays 0)

    def origin(self, pose: tuple[float, float, float]) -> np.ndarray:
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array(
            [x + c * self.spec.x - s * self.spec.y, y + s * self.spec.x + c * self.spec.y, self.spec.height]
        )

    def true_ranges(self, model: mujoco.MjModel, data: mujoco.MjData, pose: tuple[float, float, float]) -> np.ndarray:
        """Noise-free range per beam (inf beyond range_max or with no hit)."""
        spec = self.spec
        a = pose[2] + self._angles
        vec = self._vec
        np.cos(a, out=vec[:, 0])
        np.sin(a, out=vec[:, 1])
        mujoco.mj_multiRay(
            model,
            data,
            self.origin(pose),
            vec.reshape(-1),
            self._groups,
            1,
            -1,
            self._geomid,
            self._dist,
            None,
            spec.beams,
            spec.range_max,
        )
        ranges = self._dist.copy()
        ranges[(self._geomid < 0) | (ranges < 0) | (ranges > spec.range_max)] = np.inf
        return ranges

    def scan(self, model: mujoco.MjModel, data: mujoco.MjData, pose: tuple[float, float, float], stamp: float) -> Scan:
        spec = self.spec
        ranges = self.true_ranges(model, data, pose)
        finite = np.isfinite(ranges)
        ranges[finite] += self.rng.normal(0.0, spec.noise, int(finite.sum()))
        ranges[finite & (ranges < spec.range_min)] = -np.inf  # too close (REP 117)
        return Scan(ranges, spec.angle_min, spec.angle_increment, spec.range_min, spec.range_max, stamp)
