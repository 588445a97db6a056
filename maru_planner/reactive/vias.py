"""The paper's via-point handling (sec. 4-5): IsSort filter and the inserted avoidance via."""

from __future__ import annotations

import numpy as np


def is_sort(candidate, current, radius: float = 0.5, rule: str = "either_axis") -> bool:
    """IsSort (Fig. 27): may ``candidate`` replace ``current`` as the robot's next target?

    ``rule="either_axis"`` is the paper's code: the candidate is dropped when
    it lies within ``radius`` of the current target on the x axis *or* on the
    y axis. ``rule="both_axes"`` drops it only inside the square (both axes
    within ``radius``).
    """
    dx = abs(float(candidate[0]) - float(current[0]))
    dy = abs(float(candidate[1]) - float(current[1]))
    if rule == "either_axis":
        return not (dx < radius or dy < radius)
    if rule == "both_axes":
        return not (dx < radius and dy < radius)
    raise ValueError(f"is_sort rule must be 'either_axis' or 'both_axes', got {rule!r}")


class ViaTarget:
    """The single avoidance via inserted as the next target (SortPosition, Fig. 26).

    One via at most: a new obstacle event replaces it only if IsSort accepts
    it; it is dropped when reached, passed, or when an obstacle point comes
    within ``blocked_radius`` of it. Then the robot turns back to its path/goal.
    """

    def __init__(self, reach: float, blocked_radius: float):
        self.reach = reach
        self.blocked_radius = blocked_radius
        self.point: np.ndarray | None = None
        self.filtered = 0

    def clear(self) -> None:
        self.point = None

    @property
    def active(self) -> bool:
        return self.point is not None

    def offer(self, candidate, current, radius: float, rule: str) -> bool:
        """Insert ``candidate`` if IsSort accepts it against ``current`` (the target in use)."""
        if is_sort(candidate, current, radius, rule):
            self.point = np.asarray(candidate, dtype=float)[:2].copy()
            return True
        self.filtered += 1
        return False

    def refresh(self, position, heading_to_goal, points: np.ndarray) -> None:
        """Drop the via if reached, passed (behind the robot w.r.t. the goal) or blocked."""
        if self.point is None:
            return
        offset = self.point - np.asarray(position[:2], dtype=float)
        if np.hypot(*offset) < self.reach or float(np.dot(offset, heading_to_goal)) < 0.0:
            self.point = None
            return
        if len(points):
            d = np.min(np.hypot(points[:, 0] - self.point[0], points[:, 1] - self.point[1]))
            if d < self.blocked_radius:
                self.point = None
