"""``trapezoid``: stop at every waypoint, each segment a synchronised trapezoidal speed profile.

Each segment between consecutive waypoints is a straight joint-space line traversed with a synchronised
trapezoidal (or triangular) speed profile that starts and ends at rest, so every joint stays within
``velocity_limit × velocity_scaling`` and ``acceleration_limit × acceleration_scaling`` exactly. Stopping at
waypoints costs time but is safe for any path; shortcutting first keeps the number of stops small. Blended,
time-optimal and jerk-limited alternatives: :mod:`~maru_planner.trajectory.toppra`,
:mod:`~maru_planner.trajectory.ruckig`.
"""

from __future__ import annotations

import numpy as np

from maru_planner.trajectory.limits import Limits
from maru_planner.trajectory.trajectory import Trajectory


def trapezoid_trajectory(waypoints, joint_names, limits: Limits, dt: float, max_points: int) -> Trajectory:
    """:func:`time_parameterize` of ``waypoints`` under ``limits`` (a single waypoint: standing still there)."""
    if len(waypoints) < 2:
        waypoints = np.vstack([waypoints, waypoints])
    return time_parameterize(waypoints, joint_names, limits.velocity, limits.acceleration, dt=dt, max_points=max_points)


def time_parameterize(
    path: np.ndarray,
    joint_names,
    velocity_limits,
    acceleration_limits,
    velocity_scaling: float = 1.0,
    acceleration_scaling: float = 1.0,
    dt: float = 0.05,
    max_points: int = 10_000,
) -> Trajectory:
    """Rest-to-rest trapezoidal trajectory through ``path`` sampled every ``dt`` s (+ every waypoint).

    The sample period grows past ``dt`` when the duration would need more than ``max_points``
    points (every waypoint is still a sample, so a path with more segments than that gets one more
    sample per segment). All segments in one set of array operations.
    """
    path = np.asarray(path, float)
    vmax = np.asarray(velocity_limits, float) * velocity_scaling
    amax = np.asarray(acceleration_limits, float) * acceleration_scaling
    deltas = np.diff(path, axis=0)
    duration, sd, sdd, ta = _segment_profiles(deltas, vmax, amax)
    ends = np.cumsum(duration)  # in order, as the samples' times add up
    starts = np.concatenate([[0.0], ends[:-1]])
    period = max(dt, float(ends[-1] if len(ends) else 0.0) / max(1, max_points - 1 - len(deltas)))
    moving = np.flatnonzero(duration > 0.0)
    n = np.maximum(1, np.ceil(duration[moving] / period)).astype(int)
    last = np.cumsum(n) - 1  # each segment's last sample
    seg = np.repeat(moving, n)  # each sample's segment
    step = np.arange(len(seg)) - np.repeat(last - n, n)  # 1..n within its segment
    t = step * (duration[seg] / n.repeat(n))  # np.linspace's arithmetic
    t[last] = duration[moving]
    s, v, a = _trapezoid_states(t, duration[seg], sd[seg], sdd[seg], ta[seg])
    positions = path[seg] + s[:, None] * deltas[seg]
    positions[last] = path[moving + 1]  # exactly, not up to rounding
    velocities = np.vstack([np.zeros((1, path.shape[1])), v[:, None] * deltas[seg]])
    velocities[-1] = 0.0
    return Trajectory(
        joint_names=list(joint_names),
        times=np.concatenate([[0.0], starts[seg] + t]),
        positions=np.vstack([path[:1], positions]),
        velocities=velocities,
        accelerations=np.vstack([np.zeros((1, path.shape[1])), a[:, None] * deltas[seg]]),
    )


def _segment_profiles(deltas: np.ndarray, vmax: np.ndarray, amax: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per segment (row of ``deltas``), its rest-to-rest move: duration, peak path speed ``sd``, path acceleration
    ``sdd`` and acceleration time ``ta`` (all 0 for a segment that does not move)."""
    size = np.abs(deltas)
    moving = size > 1e-12
    with np.errstate(divide="ignore"):
        sd = np.where(moving, vmax / size, np.inf).min(axis=1, initial=np.inf)
        sdd = np.where(moving, amax / size, np.inf).min(axis=1, initial=np.inf)
    still = ~moving.any(axis=1)
    sd[still], sdd[still] = 1.0, 1.0  # placeholders, zeroed below
    triangular = sd * sd / sdd >= 1.0  # the peak speed is never reached
    ta = np.where(triangular, np.sqrt(1.0 / sdd), sd / sdd)
    duration = np.where(triangular, 2.0 * ta, 1.0 / sd + ta)
    sd = np.where(triangular, sdd * ta, sd)
    for values in (duration, sd, sdd, ta):
        values[still] = 0.0
    return duration, sd, sdd, ta


def _trapezoid_states(t: np.ndarray, duration: np.ndarray, sd: np.ndarray, sdd: np.ndarray, ta: np.ndarray):
    """s(t), ṡ(t), s̈(t) of each sample's trapezoid (``t`` from its segment's start; the others per sample)."""
    acc = t < ta
    dec = t > duration - ta
    td = duration - t
    s = np.where(dec, 1.0 - 0.5 * sdd * td**2, np.where(acc, 0.5 * sdd * t**2, 0.5 * sdd * ta**2 + sd * (t - ta)))
    v = np.where(dec, sdd * td, np.where(acc, sdd * t, sd))
    a = np.where(dec, -sdd, np.where(acc, sdd, 0.0))
    return np.clip(s, 0.0, 1.0), v, a
