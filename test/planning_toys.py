"""Small 2-D worlds implementing the checker protocol, for planning tests without a robot model."""

from __future__ import annotations

import numpy as np


class BoxWorldChecker:
    """Points in [0, 1]^d colliding with axis-aligned boxes (lo, hi) in the first two coordinates."""

    def __init__(self, boxes):
        self.boxes = [(np.asarray(lo, float), np.asarray(hi, float)) for lo, hi in boxes]
        self.check_count = 0
        self.scene = None

    def _hits(self, Q: np.ndarray) -> np.ndarray:
        Q = np.atleast_2d(Q)
        hit = np.zeros(len(Q), dtype=bool)
        for lo, hi in self.boxes:
            hit |= np.all((Q[:, :2] > lo) & (Q[:, :2] < hi), axis=1)
        return hit

    def is_valid(self, q) -> bool:
        self.check_count += 1
        return not bool(self._hits(np.asarray(q, float))[0])

    def are_valid(self, Q) -> np.ndarray:
        self.check_count += len(Q)
        return ~self._hits(np.asarray(Q, float))

    def first_invalid(self, Q) -> int:
        hits = self._hits(np.asarray(Q, float))
        idx = np.flatnonzero(hits)
        self.check_count += len(Q) if not len(idx) else int(idx[0]) + 1
        return int(idx[0]) if len(idx) else -1

    def colliding_pairs(self, q):
        q = np.asarray(q, float)
        return [("robot", f"box{i}") for i, (lo, hi) in enumerate(self.boxes) if np.all((q[:2] > lo) & (q[:2] < hi))]

    def clearance(self, q) -> float:
        return 0.0 if self._hits(np.asarray(q, float))[0] else 1.0

    def reset_count(self) -> None:
        self.check_count = 0

    def set_scene(self, scene) -> None:
        self.scene = scene
        if scene is not None and hasattr(scene, "boxes"):
            self.boxes = [(np.asarray(lo, float), np.asarray(hi, float)) for lo, hi in scene.boxes]


def maze_checker() -> BoxWorldChecker:
    """A 2-D maze in [0, 1]^2: three walls force an S-shaped path from (0.05, 0.05) to (0.95, 0.95)."""
    return BoxWorldChecker(
        [
            ((0.2, -0.1), (0.3, 0.8)),  # wall from the bottom, gap at the top
            ((0.5, 0.2), (0.6, 1.1)),  # wall from the top, gap at the bottom
            ((0.75, -0.1), (0.85, 0.8)),  # wall from the bottom, gap at the top
        ]
    )


def closed_maze_checker() -> BoxWorldChecker:
    """The maze with its last gap closed: the goal corner is unreachable."""
    return BoxWorldChecker(
        [
            ((0.2, -0.1), (0.3, 0.8)),
            ((0.5, 0.2), (0.6, 1.1)),
            ((0.75, -0.1), (0.85, 1.1)),
        ]
    )


class ToyRobot:
    """The slice of the RobotModel API the planner uses, for a point robot in [0, 1]^dim."""

    def __init__(self, dim: int = 2):
        self.joint_names = [f"j{i}" for i in range(dim)]
        self.nq = dim
        self.lower_limits = np.zeros(dim)
        self.upper_limits = np.ones(dim)
        self.velocity_limits = np.full(dim, 1.0)
        self.acceleration_limits = np.full(dim, 2.0)
        self.groups = {"all": list(self.joint_names), "first": [self.joint_names[0]]}
        self.end_effectors = {}

    def group_joint_indices(self, group: str):
        from maru_planner.errors import InvalidGroup

        if group not in self.groups:
            raise InvalidGroup(f"unknown group {group!r}; known: {', '.join(self.groups)}")
        return [self.joint_names.index(j) for j in self.groups[group]]

    def neutral(self):
        return np.full(self.nq, 0.5)
