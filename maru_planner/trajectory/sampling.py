"""Sampling timed sections into one :class:`Trajectory`, with at most ``max_points`` points.

The sample period grows past ``dt`` when the duration would need more points.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from maru_planner import errors
from maru_planner.trajectory.trajectory import Trajectory

SAMPLE_CHUNK = 128  # points sampled between two looks at the deadline (a ruckig point: up to ~1 ms)


class TimedSection(Protocol):
    """A timed stretch of motion between two stops (a toppra profile, a sequence of Ruckig pieces)."""

    @property
    def duration(self) -> float: ...

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


def sample(sections: Sequence[TimedSection], joint_names, end: np.ndarray, dt: float, max_points: int,
           deadline: float | None = None) -> Trajectory:  # fmt: skip
    """Concatenate the sections sampled every ``dt`` (or coarser: at most ``max_points`` points).

    PlanningTimedOut when ``deadline`` passes while sampling (10,000 ruckig points take ~1 s).
    """
    durations = np.array([section.duration for section in sections])
    period = max(dt, durations.sum() / max(1, max_points - 1 - len(sections)))
    times, pos, vel, acc = [np.zeros(1)], [], [], []
    t0 = 0.0
    for index, (section, duration) in enumerate(zip(sections, durations, strict=True)):
        t = np.linspace(0.0, duration, max(1, math.ceil(duration / period)) + 1)
        q, qd, qdd = _state_in_chunks(section, t if index == 0 else t[1:], deadline)
        pos.append(q)
        vel.append(qd)
        acc.append(qdd)
        times.append(t0 + t[1:])
        t0 += duration
    positions, velocities = np.vstack(pos), np.vstack(vel)
    positions[-1], velocities[-1] = end, 0.0
    return Trajectory(list(joint_names), np.concatenate(times), positions, velocities, np.vstack(acc))


def _state_in_chunks(section: TimedSection, t: np.ndarray, deadline: float | None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    parts = []
    for first in range(0, len(t), SAMPLE_CHUNK):
        if deadline is not None and time.monotonic() > deadline:
            raise errors.PlanningTimedOut(f"the budget ran out while sampling {len(t)} trajectory points")
        parts.append(section.state(t[first : first + SAMPLE_CHUNK]))
    return tuple(np.concatenate([part[j] for part in parts]) for j in range(3))  # type: ignore[return-value]
