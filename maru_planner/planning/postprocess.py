"""Post-processing of a joint-space path: shortcut simplification, metrics, time parameterisation.

Simplification never leaves the free space: every shortcut edge is checked with the same batched
edge check (and resolution) as the planner's motion validator before it replaces a sub-path.

Time parameterisation: each segment between consecutive waypoints is a straight joint-space line
traversed with a synchronised trapezoidal (or triangular) speed profile that starts and ends at
rest, so every joint stays within ``velocity_limit × velocity_scaling`` and
``acceleration_limit × acceleration_scaling`` exactly. Stopping at waypoints costs time but is
safe for any path; shortcutting first keeps the number of stops small. Blended, time-optimal and
jerk-limited alternatives are in :mod:`maru_planner.planning.timing`.
"""

from __future__ import annotations

import math
import time

import numpy as np

from maru_planner.planning.types import Trajectory

# rad: farthest a waypoint drop_collinear leaves out may be from the line that replaces it (bodies then move at most
# ~their levers x this: far within the 1e-6 m tolerance every certified bound gives away)
COLLINEAR_OFFSET = 1e-9


def path_length(path: np.ndarray) -> float:
    """Sum of Euclidean joint-space segment lengths (rad)."""
    if len(path) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


def smoothness(path: np.ndarray) -> float:
    """OMPL's ``PathGeometric::smoothness``: Σ (2·turn angle / (a + b))² over waypoint triples (0 = straight)."""
    path = np.asarray(path, dtype=float)
    if len(path) < 3:
        return 0.0
    a = np.linalg.norm(path[1:-1] - path[:-2], axis=1)
    b = np.linalg.norm(path[2:] - path[1:-1], axis=1)
    c = np.linalg.norm(path[2:] - path[:-2], axis=1)
    turns = (a >= 1e-12) & (b >= 1e-12)  # a repeated waypoint has no turn
    cos_value = (a * a + b * b - c * c) / np.where(turns, 2.0 * a * b, 1.0)
    turns &= (cos_value > -1.0) & (cos_value < 1.0)
    k = 2.0 * (math.pi - np.arccos(cos_value[turns])) / (a + b)[turns]
    return float(np.sum(k * k))


def drop_collinear(path: np.ndarray, tol: float = 1e-9, max_offset: float = COLLINEAR_OFFSET) -> np.ndarray:
    """Remove interior waypoints lying on the straight line between their neighbours (no checks needed): each one
    within ``max_offset`` (rad) of the segment between the waypoints kept around it.

    A waypoint goes when its steps in and out point the same way (``tol``, on their dot product) or its step in is
    shorter than ``tol``; then, Douglas-Peucker, between two kept waypoints the farthest one more than
    ``max_offset`` off their segment is kept too, until none is (so small turns do not add up to a dropped bend).
    """
    if len(path) < 3:
        return path
    step = np.diff(path, axis=0)
    norms = np.linalg.norm(step, axis=1)
    na, nb = norms[:-1], norms[1:]
    dots = np.einsum("ij,ij->i", step[:-1], step[1:])
    on_line = (na < tol) | ((nb > tol) & (np.abs(dots - na * nb) <= tol * np.maximum(1.0, na * nb)))
    keep = np.flatnonzero(np.concatenate([[True], ~on_line, [True]]))
    while len(keep) < len(path):
        off = _offsets(path, keep)
        worst = np.maximum.reduceat(off, keep[:-1])  # per kept segment (its start's offset is 0)
        far = worst > max_offset
        if not far.any():
            break
        extra = [a + int(np.argmax(off[a:b])) for a, b in zip(keep[:-1][far], keep[1:][far], strict=True)]
        keep = np.sort(np.concatenate([keep, extra]))
    return path[keep]


def _offsets(path: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Per row of ``path``, its distance from the segment between the ``keep`` rows around it (0 for kept rows)."""
    rows = np.arange(len(path))
    before = keep[np.maximum(np.searchsorted(keep, rows, side="right") - 1, 0)]
    after = keep[np.minimum(np.searchsorted(keep, rows), len(keep) - 1)]
    span, rel = path[after] - path[before], path - path[before]
    t = np.clip(np.einsum("ij,ij->i", rel, span) / np.maximum(np.einsum("ij,ij->i", span, span), 1e-300), 0.0, 1.0)
    return np.linalg.norm(rel - t[:, None] * span, axis=1)


def shortcut(path: np.ndarray, edge_valid, rng: np.random.Generator, deadline: float, max_tries: int = 200):
    """Random shortcutting: join two random waypoints when the straight edge between them is free.

    ``edge_valid(qa, qb)`` is the batched motion check. The direct start→goal edge is tried first. Stops after
    ``max_tries`` failed tries in a row, at ``deadline``, or once every pair of the path has failed (a pair that
    failed is not checked again: its edge is the same). Returns (path, edge checks made).
    """
    path = drop_collinear(np.asarray(path, float))
    checks = 0
    if len(path) > 2:
        checks += 1
        if edge_valid(path[0], path[-1]):
            return path[[0, -1]], checks
    live = list(range(len(path)))  # the kept waypoints, as indices into path
    failed = {(0, len(path) - 1)}
    untried = _untried_pairs(live, failed)
    failures = 0
    while untried and failures < max_tries and time.monotonic() < deadline:
        i, j = sorted(rng.choice(len(live), size=2, replace=False))
        pair = (live[i], live[j])
        if j - i < 2 or pair in failed:
            failures += 1
            continue
        checks += 1
        if edge_valid(path[pair[0]], path[pair[1]]):
            live = live[: i + 1] + live[j:]
            untried = _untried_pairs(live, failed)
            failures = 0
        else:
            failed.add(pair)
            untried -= 1
            failures += 1
    return drop_collinear(path[live]), checks


def _untried_pairs(live: list[int], failed: set[tuple[int, int]]) -> int:
    """Pairs of the path ``live`` that skip a waypoint and have not failed."""
    m = len(live)
    return sum((live[i], live[j]) not in failed for i in range(m) for j in range(i + 2, m))


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
