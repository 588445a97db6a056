"""Last checks between the elastic strip and the wheels: the chassis rectangle against the latest scan.

The strip plans for a disc smaller than the Jackal's circumradius (else it would not fit BARN's gaps),
so a turn can swing a corner into a cylinder. :class:`SafetyFilter` rolls each candidate twist
forward over a short horizon and keeps the first one whose rectangle (plus a margin) stays clear of
every scan point: the command, then slower versions of it, then the turn alone, then a stop.
:class:`StuckMonitor` says when the odometry has barely moved for a while (the stack then backs up
and clears its map, as Nav2's recoveries do).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np


class SafetyFilter:
    """Keeps commands whose swept rectangle stays ``margin`` off the scan points over ``horizon`` seconds."""

    def __init__(self, half_length: float, half_width: float, margin: float = 0.03, horizon: float = 0.35):
        self.half = np.array([half_length, half_width])
        self.margin = margin
        self.horizon = horizon
        self.reach = math.hypot(*self.half) + margin + 2.0 * horizon + 0.1

    def clearance(self, points: np.ndarray, pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> float:
        """Distance from the rectangle at ``pose`` (base_link) to the nearest point (< 0 inside)."""
        if len(points) == 0:
            return math.inf
        x, y, th = pose
        c, s = math.cos(th), math.sin(th)
        dx, dy = points[:, 0] - x, points[:, 1] - y
        gap_x = np.abs(c * dx + s * dy) - self.half[0]
        gap_y = np.abs(-s * dx + c * dy) - self.half[1]
        outside = np.hypot(np.maximum(gap_x, 0.0), np.maximum(gap_y, 0.0))
        return float(np.min(outside + np.minimum(np.maximum(gap_x, gap_y), 0.0)))

    def swept_clearance(self, v: float, w: float, points: np.ndarray, steps: int = 6) -> float:
        """The smallest :meth:`clearance` while driving (v, w) for the horizon."""
        if len(points) == 0:
            return math.inf
        x = y = th = 0.0
        dt = self.horizon / steps
        poses = np.empty((steps, 4))  # x, y, cos, sin of each pose along the arc
        for i in range(steps):
            x += v * math.cos(th + 0.5 * w * dt) * dt
            y += v * math.sin(th + 0.5 * w * dt) * dt
            th += w * dt
            poses[i] = (x, y, math.cos(th), math.sin(th))
        # every pose at once: the same arithmetic as clearance() per pose, one row each
        c, s = poses[:, 2:3], poses[:, 3:4]
        dx, dy = points[None, :, 0] - poses[:, :1], points[None, :, 1] - poses[:, 1:2]
        gap_x = np.abs(c * dx + s * dy) - self.half[0]
        gap_y = np.abs(-s * dx + c * dy) - self.half[1]
        outside = np.hypot(np.maximum(gap_x, 0.0), np.maximum(gap_y, 0.0))
        return float(np.min(outside + np.minimum(np.maximum(gap_x, gap_y), 0.0)))

    def is_safe(self, v: float, w: float, points: np.ndarray, margin: float | None = None) -> bool:
        """``points`` (n, 2) in base_link; True if the rectangle driven at (v, w) keeps ``margin`` off them."""
        margin = self.margin if margin is None else margin
        return len(points) == 0 or self.swept_clearance(v, w, points) >= margin

    def filter(self, v: float, w: float, points: np.ndarray) -> tuple[float, float, bool]:
        """The first safe of (v, w), (0.6 v, w), (0.3 v, w), (0, w), (0.3 v, 0) with the margin, then with a
        third of it (squeezing through); else the escape that gains the most clearance; else a stop.
        True if the command was changed."""
        near = points[np.einsum("ij,ij->i", points, points) < self.reach**2] if len(points) else points
        if len(near) == 0:
            return v, w, False
        for margin in (self.margin, self.margin / 3):
            for scale_v, scale_w in ((1.0, 1.0), (0.6, 1.0), (0.3, 1.0), (0.0, 1.0), (0.3, 0.0)):
                if self.is_safe(v * scale_v, w * scale_w, near, margin):
                    return v * scale_v, w * scale_w, (scale_v, scale_w, margin) != (1.0, 1.0, self.margin)
        now = self.clearance(near)
        escapes = [(0.3 * v, w), (0.0, w), (0.15, 0.0), (-0.15, 0.0), (0.0, 0.8), (0.0, -0.8)]
        best, best_gain = (0.0, 0.0), 0.0
        for cand in escapes:
            gain = self.swept_clearance(*cand, near) - now
            if gain > best_gain + 1e-4:
                best, best_gain = cand, gain
        return best[0], best[1], True


class StuckMonitor:
    """True when the odometry moved less than ``distance`` over the last ``window`` seconds."""

    def __init__(self, window: float = 4.0, distance: float = 0.15):
        self.window = window
        self.distance = distance
        self._history: deque[tuple[float, float, float]] = deque()

    def update(self, now: float, x: float, y: float) -> bool:
        self._history.append((now, x, y))
        while self._history and now - self._history[0][0] > self.window:
            self._history.popleft()
        t0, x0, y0 = self._history[0]
        return now - t0 >= 0.95 * self.window and math.hypot(x - x0, y - y0) < self.distance

    def reset(self) -> None:
        self._history.clear()
