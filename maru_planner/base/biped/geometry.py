"""Gait-rectangle collision checks on a :class:`BipedMap2D`."""

from __future__ import annotations

import math

import numpy as np

from maru_planner.base.common import wrap_angle
from maru_planner.errors import TooLarge

# Sample points of one rectangle test; a bigger gait rectangle (for the map's resolution) is refused.
MAX_RECTANGLE_SAMPLES = 200_000


class RectangleChecker:
    """Tests a rectangle (length along the heading, width across) against occupied cells.

    The rectangle is sampled on a lattice no coarser than half a cell,
    edges included; a pose outside the map collides.
    """

    def __init__(self, occupied: np.ndarray, resolution: float, origin, length: float, width: float):
        self.occupied = occupied
        self.resolution = resolution
        self.origin = origin
        step = resolution / 2
        nu = max(2, int(math.ceil(length / step)) + 1)
        nv = max(2, int(math.ceil(width / step)) + 1)
        if nu * nv > MAX_RECTANGLE_SAMPLES:
            raise TooLarge(
                f"a {length:g} x {width:g} m gait rectangle on {resolution:g} m cells needs {nu * nv} "
                f"samples per check, over the limit of {MAX_RECTANGLE_SAMPLES}"
            )
        u, v = np.meshgrid(np.linspace(-length / 2, length / 2, nu), np.linspace(-width / 2, width / 2, nv))
        self.local = np.column_stack([u.ravel(), v.ravel()])
        self.checks = 0

    def points(self, x: float, y: float, theta: float) -> np.ndarray:
        c, s = math.cos(theta), math.sin(theta)
        return self.local @ np.array([[c, s], [-s, c]]) + (x, y)

    def collides(self, x: float, y: float, theta: float) -> bool:
        self.checks += 1
        pts = self.points(x, y, theta)
        cols = np.floor((pts[:, 0] - self.origin[0]) / self.resolution).astype(int)
        rows = np.floor((pts[:, 1] - self.origin[1]) / self.resolution).astype(int)
        h, w = self.occupied.shape
        if rows.min() < 0 or cols.min() < 0 or rows.max() >= h or cols.max() >= w:
            return True
        return bool(self.occupied[rows, cols].any())

    def sweep_collides(self, poses: np.ndarray, max_step: float, max_turn: float = math.radians(3)) -> bool:
        """Checks the straight/rotating motion through ``poses`` (n, 3), interpolated finely."""
        for a, b in zip(poses[:-1], poses[1:]):
            dist = math.hypot(b[0] - a[0], b[1] - a[1])
            turn = wrap_angle(b[2] - a[2])
            n = max(1, int(math.ceil(max(dist / max_step, abs(turn) / max_turn))))
            for t in np.linspace(0.0, 1.0, n + 1)[1:]:
                if self.collides(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * turn):
                    return True
        return bool(len(poses) and self.collides(*poses[0]))
