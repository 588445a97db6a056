"""``ruckig``: a jerk-limited motion through the blended curve, one Ruckig trajectory per piece.

It passes through the blend boundaries with toppra's speed there and zero acceleration (straight pieces are
phase-synchronised and therefore straight). Its curve over a blend is Ruckig's, not the parabola: it is re-checked,
its deviation measured and its joints' extremes found; a corner where it collides, deviates more than allowed or
leaves the range of a joint over the path's waypoints (a joint turning near its limit: Ruckig's time-synchronised
curve can swing past the turn, and the community Ruckig has no position limits) is shrunk like a toppra blend, and
the last resort is to stop at that corner (straight, rest-to-rest). So the motion stays within the joint limits
the waypoints keep.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import ruckig

from maru_planner.trajectory.blends import BlendedPath, blend_half_lengths, deviation_from_path, sections
from maru_planner.trajectory.corners import BLEND_RETRIES, BLEND_SHRINK, count_corners
from maru_planner.trajectory.curves import Check
from maru_planner.trajectory.limits import Limits
from maru_planner.trajectory.report import ParameterizationFailed, TimingReport
from maru_planner.trajectory.toppra import toppra_section

RUCKIG_DURATION = 100.0  # s: longer sections are computed sped up and played back slower (RuckigPieces)


@dataclass
class RuckigPieces:
    """Consecutive Ruckig trajectories (each from one via state to the next), run ``time_scale`` × slower.

    Ruckig rejects very long trajectories, so a slow section is computed under limits sped up by
    ``time_scale`` (velocity ×k, acceleration ×k², jerk ×k³) and played back k times slower: the same
    path, within the real limits.
    """

    trajectories: list
    peak_speed: float  # the largest joint velocity limit: bounds every joint's speed
    time_scale: float = 1.0

    @property
    def durations(self) -> np.ndarray:
        return np.array([tr.duration for tr in self.trajectories]) * self.time_scale

    @property
    def duration(self) -> float:
        return float(self.durations.sum())

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        starts = np.concatenate([[0.0], np.cumsum(self.durations)])
        k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.trajectories) - 1)
        local = np.minimum(t - starts[k], self.durations[k]) / self.time_scale
        rows = [self.trajectories[i].at_time(float(ti)) for i, ti in zip(k, local, strict=True)]
        q, qd, qdd = (np.array([row[j] for row in rows]) for j in range(3))
        return q, qd / self.time_scale, qdd / self.time_scale**2


def ruckig_sections(waypoints, limits: Limits, check: Check, max_deviation: float
                    ) -> tuple[list[RuckigPieces], TimingReport]:  # fmt: skip
    """The Ruckig motion of each section between stops of ``waypoints``, its curves checked by ``check``."""
    report = TimingReport("ruckig")
    deviation = np.full(len(waypoints), max_deviation)
    deviation[[0, -1]] = 0.0
    for attempt in range(BLEND_RETRIES + 2):
        half = blend_half_lengths(waypoints, deviation)
        timed = [_ruckig_section(BlendedPath(w, h), limits) for w, h in sections(waypoints, half)]
        failing = _failing_corners(timed, waypoints, half, max_deviation, check, limits, report)
        if not failing:
            break
        last = attempt >= BLEND_RETRIES
        for k in failing:
            report.fallbacks.append(f"ruckig blend at waypoint {k} not certified at deviation {deviation[k]:.3g} rad")
            deviation[k] = 0.0 if last else deviation[k] / BLEND_SHRINK
    else:
        raise ParameterizationFailed(f"ruckig: no certified motion near waypoint(s) {failing}, even at rest there")
    count_corners(waypoints, half, report)
    return [pieces for pieces, _ in timed], report


def _ruckig_section(path: BlendedPath, limits: Limits) -> tuple[RuckigPieces, list[int]]:
    """Ruckig through the section's piece boundaries (see :func:`_via_speeds`); also each piece's blend waypoint.

    A straight piece is a one-joint Ruckig trajectory along the line (so it stays on it; Ruckig's own phase
    synchronisation gave up on lines whose joints have unequal limits), a blend a time-synchronised one.
    """
    speed, toppra_duration = _via_speeds(path, limits)
    k = max(1.0, toppra_duration / RUCKIG_DURATION)
    fast = Limits(limits.velocity * k, limits.acceleration * k**2, limits.jerk * k**3)
    ends = list(path.p0) + [path.end]
    directions = list(path.v0) + [np.zeros(path.dof)]
    pieces = []
    for i in range(len(path.p0)):
        v0, v1 = speed[i] * k, speed[i + 1] * k
        if path.blend_of[i] < 0:
            length = float(np.linalg.norm(ends[i + 1] - ends[i]))
            line = _ruckig_trajectory([0.0], [length], [v0], [v1], _along(path.v0[i], fast), i)
            pieces.append(_LinePiece(ends[i], path.v0[i], line))
        else:
            pieces.append(_ruckig_trajectory(ends[i], ends[i + 1], directions[i] * v0, directions[i + 1] * v1, fast, i))
    return RuckigPieces(pieces, float(np.max(limits.velocity)), k), list(path.blend_of)


def _ruckig_trajectory(start, end, start_velocity, end_velocity, limits: Limits, piece: int):
    """Ruckig's time-optimal jerk-limited trajectory between two states at zero acceleration."""
    dof = len(limits.velocity)
    inp = ruckig.InputParameter(dof)
    inp.current_position, inp.target_position = start, end
    inp.current_velocity, inp.target_velocity = start_velocity, end_velocity
    inp.current_acceleration = inp.target_acceleration = np.zeros(dof)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = limits.velocity, limits.acceleration, limits.jerk
    trajectory = ruckig.Trajectory(dof)
    try:
        result = ruckig.Ruckig(dof).calculate(inp, trajectory)
    except (ValueError, ruckig.RuckigError) as exc:  # an error code the binding has no name for
        raise ParameterizationFailed(f"ruckig failed on piece {piece}: {exc}") from exc
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise ParameterizationFailed(f"ruckig: {result} on piece {piece}")
    return trajectory


def _along(direction: np.ndarray, limits: Limits) -> Limits:
    """Limits of the arc length along a unit ``direction``: the tightest joint's, projected."""
    moving = np.abs(direction) > 1e-12
    scale = np.abs(direction[moving])
    return Limits(
        np.array([np.min(limits.velocity[moving] / scale)]),
        np.array([np.min(limits.acceleration[moving] / scale)]),
        np.array([np.min(limits.jerk[moving] / scale)]),
    )


class _LinePiece:
    """A one-joint Ruckig trajectory of the arc length along a straight line, seen as joint motion."""

    def __init__(self, start: np.ndarray, direction: np.ndarray, trajectory):
        self.start, self.direction, self.trajectory = start, direction, trajectory

    @property
    def duration(self) -> float:
        return self.trajectory.duration

    def at_time(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s, sd, sdd = (values[0] for values in self.trajectory.at_time(t)[:3])
        return self.start + s * self.direction, sd * self.direction, sdd * self.direction


def _via_speeds(path: BlendedPath, limits: Limits) -> tuple[np.ndarray, float]:
    """Path speed at each piece boundary: toppra's, made reachable under the jerk limits; toppra's duration.

    A straight piece between two blends is crossed at one speed (the lower of toppra's at its
    ends: no acceleration needed); the first and last straight pieces only ask for a speed that a
    jerk-limited start (stop) reaches within their length. Otherwise Ruckig would overshoot and
    come back.
    """
    profile = toppra_section(path, limits)
    speed = np.interp(path.starts, profile.grid, profile.sd)
    speed[[0, -1]] = 0.0
    last = len(path.p0) - 1
    for i in np.flatnonzero(path.blend_of < 0):
        length = path.starts[i + 1] - path.starts[i]
        if i == 0 and i < last:
            speed[1] = min(speed[1], _reachable_speed(length, path.v0[i], limits))
        elif i == last and i > 0:
            speed[i] = min(speed[i], _reachable_speed(length, path.v0[i], limits))
        elif 0 < i < last:
            speed[i] = speed[i + 1] = min(speed[i], speed[i + 1])
    return speed, profile.duration


def _reachable_speed(length: float, direction: np.ndarray, limits: Limits) -> float:
    """Highest speed along ``direction`` a jerk-limited motion from rest reaches within ``length``."""
    moving = np.abs(direction) > 1e-12
    a = float(np.min(limits.acceleration[moving] / np.abs(direction[moving])))
    j = float(np.min(limits.jerk[moving] / np.abs(direction[moving])))
    v = (length * length * j) ** (1.0 / 3.0)  # never reaches a: d(v) = v·sqrt(v/j)
    if v > a * a / j:  # reaches a: d(v) = v²/(2a) + v·a/(2j)
        v = 0.5 * a * (math.sqrt((a / j) ** 2 + 8.0 * length / a) - a / j)
    return v


def _failing_corners(timed, waypoints, half, max_deviation, check: Check, limits: Limits, report) -> list[int]:
    """Interior waypoints whose Ruckig motion leaves the path by more than allowed, leaves the joints' range over
    ``waypoints`` or collides there.

    A piece that stays on the path (a straight one) needs no check; one that leaves it is checked whole.
    """
    t0 = time.monotonic()
    failing = set()
    low, high = waypoints.min(axis=0) - 1e-9, waypoints.max(axis=0) + 1e-9
    for pieces, blend_of in timed:
        for trajectory, corner in zip(pieces.trajectories, blend_of, strict=True):
            q, chords = _dense(trajectory, pieces, check.step, limits)
            off_path = deviation_from_path(q, waypoints)
            if off_path.max() <= 1e-9:
                continue
            report.certify_checks += len(q)
            lowest, highest = _extremes(trajectory)
            outside = bool(np.any(lowest < low) or np.any(highest > high))
            if outside or off_path.max() > max_deviation + 1e-9 or not check(q, chords):
                failing.add(int(corner) if corner >= 0 else _nearest_corner(q[off_path > 1e-9], waypoints))
    report.certify_time += time.monotonic() - t0
    return sorted(k for k in failing if 0 < k < len(waypoints) - 1)


def _extremes(trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Each joint's lowest and highest position over a piece (Ruckig's exact extrema, not samples)."""
    if isinstance(trajectory, _LinePiece):
        ends = np.array([[e.min, e.max] for e in trajectory.trajectory.position_extrema][0])
        q = trajectory.start[None] + ends[:, None] * trajectory.direction[None]
        return q.min(axis=0), q.max(axis=0)
    extrema = trajectory.position_extrema
    return np.array([e.min for e in extrema]), np.array([e.max for e in extrema])


def _nearest_corner(points: np.ndarray, waypoints: np.ndarray) -> int:
    """The interior waypoint closest to ``points`` (a straight piece overshooting past its end)."""
    if len(waypoints) < 3:
        return 0
    d = np.linalg.norm(waypoints[1:-1][None] - points[:, None], axis=2).min(axis=0)
    return int(np.argmin(d)) + 1


def _dense(trajectory, pieces: RuckigPieces, step: float, limits: Limits) -> tuple[np.ndarray, np.ndarray]:
    """Positions along one of ``pieces``' Ruckig trajectories at most ``step`` apart in every joint, and per
    joint how far it can leave the chords between them (acceleration limit × interval² / 8)."""
    duration = trajectory.duration * pieces.time_scale  # real seconds
    n = max(2, math.ceil(duration * pieces.peak_speed / step) + 1)
    q = np.array([trajectory.at_time(t)[0] for t in np.linspace(0.0, trajectory.duration, n)])
    interval = duration / (n - 1)
    return q, limits.acceleration * interval * interval / 8.0
