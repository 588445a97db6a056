"""The robot's current state: joint values by name, as the robot reports them (``/joint_states`` in the node).

:func:`configuration` turns joint values by name into a full configuration; :class:`JointStateStore` keeps the
newest value of each of the robot's joints (a request without a start state plans from it).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Collection, Sequence

import numpy as np

from maru_planner import errors
from maru_planner.robot import RobotModel


def configuration(robot: RobotModel, values: dict[str, float], *, strict: bool = False) -> np.ndarray:
    """Full robot configuration: ``robot.neutral()`` with ``values`` set by joint name.

    Names the robot does not have are ignored (``/joint_states`` may carry other joints),
    or raise ``InvalidJointNames`` when ``strict``.
    """
    q = np.asarray(robot.neutral(), dtype=float).copy()
    joints = set(robot.joint_names)
    unknown = [name for name in values if name not in joints]
    if strict and unknown:
        raise errors.InvalidJointNames(f"unknown joint(s) {', '.join(unknown)}")
    known = [name for name in values if name in joints]
    if known:
        q[robot.joint_indices(known)] = [values[name] for name in known]
    return q


class JointStateStore:
    """The newest finite value of each known joint; names it does not know are counted, never stored."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._latest: dict[str, float] = {}
        self._ignored = 0

    @property
    def ignored(self) -> int:
        """Values ignored so far (an unknown name, a non-finite value, a repeated name)."""
        with self._lock:
            return self._ignored

    def merge(self, names: Sequence[str], positions: Sequence[float], known: Collection[str]) -> int:
        """Store the values of ``known`` joints among ``names``; the number of values ignored."""
        values = {n: float(v) for n, v in zip(names, positions) if n in known and math.isfinite(v)}
        ignored = len(names) - len(values)
        with self._lock:
            self._latest.update(values)
            self._ignored += ignored
        return ignored

    def latest(self) -> dict[str, float]:
        """A copy of the newest values (empty: none received)."""
        with self._lock:
            return dict(self._latest)

    def clear(self) -> None:
        """Forget the values (not the count of ignored ones)."""
        with self._lock:
            self._latest.clear()
