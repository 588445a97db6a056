"""Time parameterisation of a certified joint-space path: ``toppra`` | ``ruckig`` | ``trapezoid``.

``trapezoid`` (:func:`postprocess.time_parameterize`) stops at every waypoint. The other two
first replace each corner by a parabolic blend: a quadratic Bézier from ``P − l·u_in`` through
control point ``P`` to ``P + l·u_out``, whose distance from the corner, ``l·|u_out − u_in| / 4``,
is at most the requested deviation (and ``l`` at most half of either adjacent segment). The
straight parts of the blended curve lie on the certified path; every blend is re-checked by
``curve_free(states, deviation)``: its samples at most ``certify_step`` apart (default
:data:`CERTIFY_STEP`) and, per joint, how far the curve leaves the chords between them (exact for
a parabola: ``|p''|·h²/8``), for a checker that certifies the chords continuously with that much
more margin; a checker of the states alone needs the fine default step. A blend that collides is retried with a
quarter of its deviation, twice; then the motion stops at that corner (the path is split there).
Past an optional deadline no blend is certified any more, so the corners left stop.

``toppra`` computes the time-optimal path velocity along the blended curve under
``velocity × scaling`` and ``acceleration × scaling`` (TOPP-RA, constant path acceleration
between grid points, which include every blend boundary). The result is then evaluated on a dense
grid and, if toppra's discretisation let a limit be exceeded, uniformly slowed down until every
limit holds at every sample it returns. A path of one straight segment skips the solver: its
time-optimal profile is the bang-coast-bang trapezoid of the limiting joint, in closed form.

``ruckig`` is jerk-limited: it passes through the blend boundaries with toppra's speed there
and zero acceleration, one Ruckig trajectory per piece (straight pieces are phase-synchronised
and therefore straight). Its curve over a blend is Ruckig's, not the parabola: it is re-checked
and its deviation measured; a corner where it collides or deviates more than allowed is shrunk
like a toppra blend, and the last resort is to stop at that corner (straight, rest-to-rest).

Every trajectory is sampled with at most ``max_points`` points: the sample period grows past
``dt`` when the duration would need more.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import ruckig
import toppra.constants
import toppra.interpolator

from maru_planner import errors
from maru_planner.planning import postprocess
from maru_planner.planning.config import TIME_PARAMETERIZATIONS
from maru_planner.planning.types import Trajectory

METHODS = TIME_PARAMETERIZATIONS
JERK_RAMP_TIME = 0.1  # s: default jerk limit = acceleration limit / this (full acceleration in 0.1 s)
CERTIFY_STEP = 0.005  # rad: joint step of the collision re-check of blends
BLEND_SHRINK = 4.0  # each retry of a colliding blend divides its deviation by this
BLEND_RETRIES = 2  # retries before a corner becomes a stop
# A blend is certified as this many bent segments: each gets its own joint-speed bound (dq/dt runs from the incoming
# to the outgoing direction). 4 took Maru-1's blend certification from 10.7 to 7.5 ms a plan (1 part) and 9.4 (8).
BLEND_BEND_PARTS = 4
SHARED_END = 1e-12  # rad: a straight part this short between two blends is their shared end (nothing to prove)
MIN_BLEND_SPEED = 0.1  # |u_in + u_out| below this (a near reversal): stop instead of blending
GRID_INTERVALS = 30  # toppra grid intervals along a section (plus ≥ BLEND_INTERVALS per blend)
BLEND_INTERVALS = 3
RATIO_TOL = 1e-9
RUCKIG_DURATION = 100.0  # s: longer sections are computed sped up and played back slower (_RuckigPieces)
# Slowest scaling a request may ask for (10,000x the full-speed duration); far below it the time
# parameterisations overflow (1e-300 gave NaN durations and internal errors).
MIN_SCALING = 1e-4

CurveFree = Callable[[np.ndarray, np.ndarray], bool]  # (states, chord deviation per joint) -> collision-free
# (states, chord deviation per joint), or with a third element, bends (states - 1, joints): segment i is the parabola
# (1 - t)·q_i + t·q_i+1 + (t² - t)·bend_i -- only for a curve check whose ``takes_bends`` is True
Curve = tuple


@dataclass(frozen=True)
class Limits:
    """Per-joint limits the trajectory must respect (already multiplied by the request's scaling)."""

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    @classmethod
    def scaled(
        cls,
        velocity_limits: Sequence[float],
        acceleration_limits: Sequence[float],
        velocity_scaling: float = 1.0,
        acceleration_scaling: float = 1.0,
        jerk_scaling: float = 1.0,
        jerk_limits: Sequence[float] | None = None,
    ) -> Limits:
        """Limits × scaling; jerk limits default to :func:`default_jerk_limits` of the acceleration limits."""
        acc = np.asarray(acceleration_limits, float)
        jerk = default_jerk_limits(acc) if jerk_limits is None else np.asarray(jerk_limits, float)
        return cls(
            np.asarray(velocity_limits, float) * velocity_scaling,
            acc * acceleration_scaling,
            jerk * jerk_scaling,
        )


@dataclass(frozen=True)
class CertifiedCurve:
    """A :data:`CurveFree` proving a group curve clear by ``margin`` on ``certifier`` (a ``PathCertifier``), each
    joint's margin grown by how far the curve leaves the chords; the joints outside ``indices`` stay at ``base``.
    ``many`` proves several curves in one certification pass (the blends of a path, and its straight pieces:
    ``takes_pieces``)."""

    certifier: Any
    base: np.ndarray
    indices: Sequence[int]
    deadline: float | None
    margin: float
    clearance: list[float] = field(default_factory=list, compare=False)  # m: least distance on each curve proven
    takes_bends = True  # the certifier proves parabolic segments as they are

    @property
    def takes_pieces(self) -> bool:
        """Worth giving the straight pieces too (then the path's certification has nothing left), except in a large
        scene: a pass keeps the obstacles near any of its curves, so every blend would be checked against the pieces'
        obstacles too (10,000-ball clutter around Maru-1: 129 -> 220 ms a plan)."""
        return not self.certifier.near_path_only

    def __call__(self, states: np.ndarray, chord_deviation: np.ndarray) -> bool:
        return self.many([(states, chord_deviation)])[0]

    def many(self, curves: Sequence[Curve]) -> list[bool]:
        certified, clearance = self.certifier.prove_curves(list(curves), self.deadline, margin=self.margin,
                                                           base=self.base, joints=self.indices)  # fmt: skip
        self.clearance.extend(clearance[certified].tolist())
        return certified.tolist()


def certified_curve(certifier: Any, base: np.ndarray, indices, deadline: float | None, margin: float) -> CurveFree:
    """:class:`CertifiedCurve` of these arguments."""
    return CertifiedCurve(certifier, base, indices, deadline, margin)


@dataclass(frozen=True)
class WatchedCurve:
    """``curve_free`` with ``before()`` called ahead of every check (a monitor's cancellation point); keeps
    ``curve_free``'s ``many``."""

    curve_free: CurveFree
    before: Callable[[], None]

    @property
    def takes_bends(self) -> bool:
        return takes_bends(self.curve_free)

    @property
    def takes_pieces(self) -> bool:
        return takes_pieces(self.curve_free)

    @property
    def clearance(self) -> list[float]:
        return getattr(self.curve_free, "clearance", [])

    def __call__(self, states: np.ndarray, chord_deviation: np.ndarray) -> bool:
        self.before()
        return self.curve_free(states, chord_deviation)

    def many(self, curves: Sequence[Curve]) -> list[bool]:
        self.before()
        return curves_free(self.curve_free, curves)


def certified_clearance(curve_free: CurveFree) -> float:
    """The smallest distance (m) measured on the curves ``curve_free`` (a :class:`CertifiedCurve`, maybe watched)
    certified; inf if none, or if it is no certifier."""
    return min(getattr(curve_free, "clearance", None) or [math.inf])


def takes_bends(curve_free: CurveFree) -> bool:
    """Whether ``curve_free`` proves curves given with bends (:data:`Curve`), else only sampled chords."""
    return bool(getattr(curve_free, "takes_bends", False))


def takes_pieces(curve_free: CurveFree) -> bool:
    """Whether ``curve_free`` should get the straight pieces of a blended curve too (a :class:`CertifiedCurve`, maybe
    watched): proven with the blends, they spare the path's certification (``TimingReport.curve_certified``)."""
    return bool(getattr(curve_free, "takes_pieces", False))


def curves_free(curve_free: CurveFree, curves: Sequence[Curve]) -> list[bool]:
    """``curve_free`` of each curve: in one call when it has ``many``, else one by one."""
    many = getattr(curve_free, "many", None)
    if many is not None:
        return list(many(curves))
    return [curve_free(states, deviation) for states, deviation in curves]


def check_scaling(value: object, name: str) -> float:
    """``value`` as a limit scaling; InvalidRequest naming ``name`` unless it is a number in [MIN_SCALING, 1]."""
    try:
        scaling = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise errors.InvalidRequest(f"{name} must be a number in [{MIN_SCALING:g}, 1], got {value!r:.40}") from exc
    if not (math.isfinite(scaling) and MIN_SCALING <= scaling <= 1.0):
        raise errors.InvalidRequest(f"{name} must be in [{MIN_SCALING:g}, 1], got {scaling:.3g}")
    return scaling


def check_method(method: str) -> str:
    """``method`` if it is one of :data:`METHODS`, else InvalidRequest naming them."""
    if method not in METHODS:
        raise errors.InvalidRequest(f"time_parameterization must be one of {', '.join(METHODS)}, got {method!r}")
    return method


def default_jerk_limits(acceleration_limits: Sequence[float] | np.ndarray) -> np.ndarray:
    """Jerk limits reaching the full acceleration in :data:`JERK_RAMP_TIME` (URDF has no jerk field)."""
    return np.asarray(acceleration_limits, float) / JERK_RAMP_TIME


@dataclass
class TimingReport:
    """How a trajectory was made: the method used, the corners blended or stopped, what the checks cost."""

    method: str
    blends: int = 0  # corners passed without stopping
    stops: int = 0  # interior waypoints where the motion stops
    max_deviation: float = 0.0  # largest distance (rad) of the blended curve from a corner it replaces
    certify_checks: int = 0  # configurations re-checked for collision
    certify_time: float = 0.0
    fallbacks: list[str] = field(default_factory=list)
    # per waypoint of the path given: the half-length (rad) of the certified parabolic blend the curve rounds it with
    # (toppra; 0: the curve passes it or stops there). None: the curve was not made of certified blends (ruckig's).
    corner_blends: np.ndarray | None = None
    min_clearance: float = math.inf  # m: smallest distance measured on the curves certified (inf: none)
    # every straight part of the curve was proven with its blends (toppra with a certifier, :func:`takes_pieces`):
    # the whole curve is certified, the path's certification has nothing left to prove
    curve_certified: bool = False


# --- geometry: the blended curve ---------------------------------------------------------------
class BlendedPath(toppra.interpolator.AbstractGeometricPath):
    """A polyline whose corners are parabolic blends; C¹ in the path parameter ``s`` (see module doc).

    Every piece is ``p(σ) = p0 + v0·σ + ½·dd·σ²`` for ``σ = s − s_start`` (lines: |v0| = 1, dd = 0).
    ``half_lengths[k]`` is the blend size ``l`` at waypoint k (> 0 for every interior waypoint).
    """

    def __init__(self, waypoints: np.ndarray, half_lengths: np.ndarray):
        units = _units(waypoints)
        inner = len(waypoints) - 2  # blends: one per interior waypoint; pieces in order line 0, blend 1, line 1, ...
        straight = np.linalg.norm(np.diff(waypoints, axis=0), axis=1) - half_lengths[:-1] - half_lengths[1:]
        blend = half_lengths[1:-1]
        line_p0 = waypoints[:-1] + half_lengths[:-1, None] * units
        blend_p0 = waypoints[1:-1] - blend[:, None] * units[:-1]
        blend_dd = (units[1:] - units[:-1]) / (2.0 * blend[:, None])
        order = np.empty(2 * inner + 1, dtype=int)  # position of each piece among [lines..., blends...]
        order[0::2], order[1::2] = np.arange(inner + 1), inner + 1 + np.arange(inner)
        keep = np.concatenate([straight > SHARED_END, np.ones(inner, dtype=bool)])[order]
        order = order[keep]
        lengths = np.concatenate([straight, 2.0 * blend])[order]
        self.starts = np.concatenate([[0.0], np.cumsum(lengths)])
        self.p0 = np.concatenate([line_p0, blend_p0])[order]
        self.v0 = np.concatenate([units, units[:-1]])[order]
        self.dd = np.concatenate([np.zeros_like(units), blend_dd])[order]
        self.blend_of = np.concatenate([np.full(inner + 1, -1), np.arange(1, inner + 1)])[order]  # -1: a line
        self.end = waypoints[-1]

    @property
    def dof(self) -> int:
        return self.p0.shape[1]

    @property
    def path_interval(self) -> np.ndarray:
        return np.array([0.0, self.starts[-1]])

    @property
    def waypoints(self):
        return self.starts, self.p0

    def __call__(self, path_positions, order: int = 0) -> np.ndarray:
        ss = np.atleast_1d(np.asarray(path_positions, float))
        piece = np.clip(np.searchsorted(self.starts, ss, side="right") - 1, 0, len(self.p0) - 1)
        out = self.at(ss, piece, order)
        return out if np.ndim(path_positions) else out[0]

    def at(self, ss: np.ndarray, piece: np.ndarray, order: int) -> np.ndarray:
        """Derivative ``order`` (0–2) at path positions ``ss`` on the given pieces."""
        sigma = (ss - self.starts[piece])[:, None]
        if order == 0:
            return self.p0[piece] + self.v0[piece] * sigma + 0.5 * self.dd[piece] * sigma**2
        if order == 1:
            return self.v0[piece] + self.dd[piece] * sigma
        if order == 2:
            return self.dd[piece].copy()
        raise ValueError(f"order must be 0, 1 or 2, got {order}")

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """toppra grid points (every piece boundary included) and the piece of each grid interval."""
        s0, lengths = self.starts[:-1], np.diff(self.starts)
        least = np.where(self.blend_of >= 0, BLEND_INTERVALS, 1)
        n = np.maximum(least, np.ceil(GRID_INTERVALS * lengths / self.starts[-1]).astype(int))
        pieces = np.repeat(np.arange(len(n)), n)
        step = np.arange(len(pieces)) - np.repeat(np.cumsum(n) - n, n)  # interval index within its piece
        points = s0[pieces] + lengths[pieces] * (step / n[pieces])
        return np.append(points, self.starts[-1]), pieces


def _units(waypoints: np.ndarray) -> np.ndarray:
    delta = np.diff(waypoints, axis=0)
    return delta / np.linalg.norm(delta, axis=1)[:, None]


def parabola_parts(start: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray, length: np.ndarray,
                   parts: int = BLEND_BEND_PARTS) -> list[Curve]:  # fmt: skip
    """Per row k, ``p(σ) = start[k] + velocity[k]·σ + ½·acceleration[k]·σ²`` on ``[0, length[k]]`` as ``parts`` bent
    segments (:data:`Curve`): ends, no chord deviation, and each part's bend ``½·h²·p''`` (h its length in σ): on it
    ``p = (1 - t)·p(start) + t·p(end) + (t² - t)·bend``. All rows in one set of array operations."""
    sigma = np.linspace(0.0, length, parts + 1, axis=1)[..., None]  # (rows, parts + 1, 1)
    ends = start[:, None] + velocity[:, None] * sigma + 0.5 * acceleration[:, None] * sigma**2
    bends = np.repeat((0.5 * ((length / parts) ** 2)[:, None] * acceleration)[:, None], parts, axis=1)
    on_chord = np.zeros(start.shape[1])
    return [(ends[k], on_chord, bends[k]) for k in range(len(length))]


def parabola_chords(start: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray, length: float,
                    step: float) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Points along the parabola of :func:`parabola_parts` at most ``step`` apart in σ (|p'| ≤ 1 on a blend, so a
    path step bounds the joint step) and, per joint, how far it leaves the chords between them (|p''|·h²/8)."""
    sigma = np.linspace(0.0, length, max(2, math.ceil(length / step) + 1))
    h = sigma[1] - sigma[0]
    points = start + velocity * sigma[:, None] + 0.5 * acceleration * sigma[:, None] ** 2
    return points, np.abs(acceleration) * h * h / 8.0


def blend_half_lengths(waypoints: np.ndarray, deviation: np.ndarray, units: np.ndarray | None = None) -> np.ndarray:
    """Blend size ``l`` at every waypoint for corner deviations ≤ ``deviation`` (one per waypoint; 0: stop there), 0
    at the ends and at near reversals; ``units``: the path's :func:`_units` if at hand."""
    half = np.zeros(len(waypoints))
    if len(waypoints) < 3:
        return half
    units = _units(waypoints) if units is None else units
    u_in, u_out = units[:-1], units[1:]
    turn = np.linalg.norm(u_out - u_in, axis=1)
    segment = np.linalg.norm(np.diff(waypoints, axis=0), axis=1)
    # A blend may take all of a first or last segment, half of a segment it shares with another blend.
    before, after = 0.5 * segment[:-1], 0.5 * segment[1:]
    before[0], after[-1] = segment[0], segment[-1]
    dev = np.asarray(deviation, dtype=float)[1:-1]
    blended = (dev > 0.0) & (np.linalg.norm(u_in + u_out, axis=1) >= MIN_BLEND_SPEED)
    with np.errstate(divide="ignore"):
        half[1:-1] = np.where(blended, np.minimum(4.0 * dev / turn, np.minimum(before, after)), 0.0)
    return half


def deviation_from_path(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Euclidean distance of each of ``points`` from the polyline ``path`` (rad)."""
    points, path = np.atleast_2d(points), np.atleast_2d(path)
    if len(path) == 1:
        return np.linalg.norm(points - path[0], axis=1)
    a, seg = path[:-1], np.diff(path, axis=0)
    length2 = np.maximum((seg * seg).sum(axis=1), 1e-300)
    rel = points[:, None, :] - a[None]
    t = np.clip((rel * seg[None]).sum(axis=2) / length2, 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * seg[None], axis=2).min(axis=1)


# --- the parameterisation entry point ---------------------------------------------------------
def parameterize(
    path: np.ndarray,
    joint_names: Sequence[str],
    limits: Limits,
    method: str,
    *,
    curve_free: CurveFree,
    max_deviation: float,
    dt: float = 0.05,
    max_points: int = 10_000,
    deadline: float | None = None,
    certify_step: float = CERTIFY_STEP,
    sample_deadline: float | None = None,
) -> tuple[Trajectory, TimingReport]:
    """Trajectory through ``path`` (rows: group configurations) by ``method`` (module doc).

    ``curve_free(Q, deviation)`` is True when the curve through the rows of ``Q`` (at most
    ``certify_step`` apart in every joint), which leaves the straight chords between consecutive rows
    by at most ``deviation[j]`` in joint j, is collision-free; it re-checks blends. ``max_deviation``
    (rad) bounds the distance of the blended curve from each corner. After ``deadline``
    (``time.monotonic()``) no more blends are checked: the corners left stop. Sampling the
    sections raises PlanningTimedOut once ``sample_deadline`` has passed (a caller's hard budget).
    """
    check_method(method)
    if not (math.isfinite(max_deviation) and max_deviation >= 0.0):
        raise errors.InvalidRequest(f"blend deviation must be a finite number >= 0 rad, got {max_deviation}")
    if max_points < 2:
        raise errors.InvalidRequest(f"max_points must be >= 2, got {max_points}")
    waypoints = _distinct(np.asarray(path, float))
    if method == "trapezoid" or len(waypoints) < 2:
        return _trapezoid(waypoints, joint_names, limits, dt, max_points), TimingReport("trapezoid")
    if method == "toppra" and len(waypoints) == 2:  # one straight segment: TOPP-RA's optimum is this trapezoid
        return _trapezoid(waypoints, joint_names, limits, dt, max_points), TimingReport("toppra")
    try:
        build = _toppra if method == "toppra" else _ruckig
        sections, report = build(waypoints, limits, _Check(curve_free, certify_step, deadline), max_deviation)
    except _ParameterizationFailed as exc:
        report = TimingReport("trapezoid", fallbacks=[f"{method}: {exc}"])
        return _trapezoid(waypoints, joint_names, limits, dt, max_points), report
    if report.corner_blends is not None:
        report.corner_blends = _at_rows(np.asarray(path, float), waypoints, report.corner_blends)
    report.min_clearance = certified_clearance(curve_free)
    return _sample(sections, joint_names, waypoints[-1], dt, max_points, sample_deadline), report


def _at_rows(path: np.ndarray, waypoints: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (one per row of ``waypoints``: rows of ``path`` in order, as :func:`_distinct` keeps them) at the
    rows of ``path`` they are (0 at the others)."""
    out, i = np.zeros(len(path)), 0
    for waypoint, value in zip(waypoints, values, strict=True):
        while not np.array_equal(path[i], waypoint):
            i += 1
        out[i] = value
        i += 1
    return out


@dataclass(frozen=True)
class _Check:
    """The caller's curve check, its sample step, and the deadline after which nothing is certified."""

    curve_free: CurveFree
    step: float
    deadline: float | None

    def __call__(self, states: np.ndarray, deviation: np.ndarray) -> bool:
        return self.many([(states, deviation)])[0]

    def many(self, curves: Sequence[Curve]) -> list[bool]:
        if self.deadline is not None and time.monotonic() >= self.deadline:
            return [False] * len(curves)
        return curves_free(self.curve_free, curves)


def _distinct(path: np.ndarray) -> np.ndarray:
    """``path`` without repeated or collinear interior waypoints: none farther than ``postprocess.COLLINEAR_OFFSET``
    from the line the curve then follows, so what certification proves of ``path`` holds for the curve."""
    if len(path) < 2:
        return path
    keep = np.concatenate([[True], np.linalg.norm(np.diff(path, axis=0), axis=1) > 1e-12])
    path = path[keep]
    return postprocess.drop_collinear(path) if len(path) > 2 else path


def _trapezoid(waypoints, joint_names, limits: Limits, dt: float, max_points: int) -> Trajectory:
    if len(waypoints) < 2:
        waypoints = np.vstack([waypoints, waypoints])
    return postprocess.time_parameterize(
        waypoints, joint_names, limits.velocity, limits.acceleration, dt=dt, max_points=max_points
    )


class _ParameterizationFailed(Exception):
    """toppra or Ruckig could not parameterise a section (numerical failure): fall back to trapezoids."""


# --- blended corners, certified --------------------------------------------------------------
def _certified_half_lengths(
    waypoints: np.ndarray, max_deviation: float, check: _Check, report: TimingReport, with_pieces: bool = False
) -> np.ndarray:
    """Blend size per waypoint (0 at the ends and at stops), every blend re-checked (module doc). ``with_pieces``:
    the checks also prove the straight pieces between the blends (:func:`_pieces_to_prove`); ``report`` tells
    whether every straight part of the final curve lies on one proven (``curve_certified``)."""
    half = np.zeros(len(waypoints))
    t0 = time.monotonic()
    deviation = np.full(len(waypoints), float(max_deviation))
    pending = list(range(1, len(waypoints) - 1))
    units = _units(waypoints)
    lengths = np.linalg.norm(np.diff(waypoints, axis=0), axis=1)
    proven_ends = np.full((len(waypoints) - 1, 2), np.inf)  # per segment: the blend sizes its proven piece left out
    for attempt in range(BLEND_RETRIES + 1):  # all pending corners in one check: they share the certification's work
        half[pending] = blend_half_lengths(waypoints, deviation, units)[pending]
        pending = [k for k in pending if half[k] > 0.0]
        if not pending:
            break
        curves = _corner_curves(waypoints, units, np.array(pending), half, check)
        report.certify_checks += sum(len(curve[0]) for curve in curves)
        segments, ends, pieces = _pieces_to_prove(waypoints, units, lengths, half, pending, attempt) if with_pieces \
            else ([], half, [])
        free = check.many(curves + pieces)
        for i, proven in zip(segments, free[len(curves) :], strict=True):
            if proven:
                proven_ends[i] = ends[i], ends[i + 1]
        failed = [k for k, ok in zip(pending, free[: len(curves)], strict=True) if not ok]
        for k in failed:
            report.fallbacks.append(f"blend at waypoint {k} not certified at deviation {deviation[k]:.3g} rad")
            half[k] = 0.0
            deviation[k] /= BLEND_SHRINK
        pending = failed
    report.certify_time += time.monotonic() - t0
    _count_corners(waypoints, half, report)
    if with_pieces:
        straight = lengths - half[:-1] - half[1:] > SHARED_END
        report.curve_certified = bool(np.all(~straight | ((proven_ends[:, 0] <= half[:-1])
                                                         & (proven_ends[:, 1] <= half[1:]))))  # fmt: skip
    return half


def _pieces_to_prove(waypoints: np.ndarray, units: np.ndarray, lengths: np.ndarray, half: np.ndarray,
                     pending: list[int], attempt: int) -> tuple[list[int], np.ndarray, list[Curve]]:  # fmt: skip
    """The segments whose straight pieces to prove with the blends of ``attempt``, the blend size left out at each
    waypoint, and the pieces as curves: first every segment without the ends its blends (``half``) take; at the
    first retry, the segments next to a retried corner, up to that corner (wherever its blend ends up, or if the
    motion stops there, the straight part left lies on them); none after."""
    if attempt == 0:
        segments, ends = np.arange(len(waypoints) - 1), half
    elif attempt == 1:
        segments = np.unique(np.concatenate([np.array(pending) - 1, pending]))
        ends = half.copy()
        ends[pending] = 0.0
    else:
        return [], half, []
    segments = segments[lengths[segments] - ends[segments] - ends[segments + 1] > SHARED_END]
    lines = np.stack([waypoints[segments] + ends[segments, None] * units[segments],
                      waypoints[segments + 1] - ends[segments + 1, None] * units[segments]], axis=1)  # fmt: skip
    return segments.tolist(), ends, [(line, np.zeros(waypoints.shape[1])) for line in lines]


def _corner_curves(waypoints: np.ndarray, units: np.ndarray, corners: np.ndarray, half: np.ndarray, check: _Check
                   ) -> list[Curve]:  # fmt: skip
    """The blends of ``corners`` (the parabolas a :class:`BlendedPath` puts there, ``half`` their sizes by waypoint)
    as ``check`` takes them: :data:`BLEND_BEND_PARTS` bent segments, else chords ``check.step`` apart."""
    u_in, u_out, h = units[corners - 1], units[corners], half[corners][:, None]
    start, acceleration = waypoints[corners] - h * u_in, (u_out - u_in) / (2.0 * h)
    if takes_bends(check.curve_free):
        return parabola_parts(start, u_in, acceleration, 2.0 * h[:, 0])
    return [parabola_chords(s, v, a, 2.0 * length, check.step)
            for s, v, a, length in zip(start, u_in, acceleration, h[:, 0], strict=True)]  # fmt: skip


def _count_corners(waypoints: np.ndarray, half: np.ndarray, report: TimingReport) -> None:
    """Blends, stops and the largest distance of a blend's middle from its corner (``l·|u_out − u_in| / 4``)."""
    interior = half[1:-1]
    report.blends = int(np.count_nonzero(interior > 0))
    report.stops = len(interior) - report.blends
    if report.blends:
        turn = np.linalg.norm(np.diff(_units(waypoints), axis=0), axis=1)
        report.max_deviation = float(np.max(0.25 * interior * turn))


def _sections(waypoints: np.ndarray, half: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(waypoints, half lengths) of each stretch between stops."""
    cuts = [0] + [k for k in range(1, len(waypoints) - 1) if half[k] == 0.0] + [len(waypoints) - 1]
    out = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        h = half[a : b + 1].copy()
        h[0] = h[-1] = 0.0
        out.append((waypoints[a : b + 1], h))
    return out


# --- toppra -----------------------------------------------------------------------------------
@dataclass
class _PathVelocity:
    """A path-velocity profile: ṡ at grid points, constant s̈ between them."""

    path: BlendedPath
    grid: np.ndarray
    pieces: np.ndarray  # piece of each grid interval
    sd: np.ndarray

    @property
    def times(self) -> np.ndarray:
        return np.concatenate([[0.0], np.cumsum(2.0 * np.diff(self.grid) / (self.sd[1:] + self.sd[:-1]))])

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint positions, velocities and accelerations at times ``t``."""
        path = self.path
        return _topp_kernel().profile_states_nb(np.asarray(t, dtype=float), self.times, self.grid, self.sd,
                                                self.pieces, path.starts, path.p0, path.v0, path.dd)  # fmt: skip

    def peak_ratios(self, limits: Limits) -> tuple[float, float]:
        """Exact maxima over the whole profile of |joint velocity| / limit and |joint acceleration| / limit
        (:func:`~maru_planner.planning.topp_kernel.peak_ratios_nb`)."""
        path = self.path
        return _topp_kernel().peak_ratios_nb(self.grid, self.sd, self.pieces, path.starts, path.v0, path.dd,
                                             limits.velocity, limits.acceleration)  # fmt: skip


def _toppra(waypoints, limits: Limits, check: _Check, max_deviation: float):
    report = TimingReport("toppra")
    half = _certified_half_lengths(waypoints, max_deviation, check, report, takes_pieces(check.curve_free))
    report.corner_blends = half
    return [_toppra_section(BlendedPath(w, h), limits) for w, h in _sections(waypoints, half)], report


def _toppra_section(path: BlendedPath, limits: Limits) -> _PathVelocity:
    grid, pieces = path.grid()
    sd = _rest_to_rest_speeds(path, grid, limits)
    if sd is None:
        raise _ParameterizationFailed("toppra: the path is not controllable (numerical failure)")
    return _within_limits(_PathVelocity(path, grid, pieces, sd), limits)


def _rest_to_rest_speeds(path: BlendedPath, grid: np.ndarray, limits: Limits) -> np.ndarray | None:
    """Path speeds ṡ at the ``grid`` points from rest to rest under the joint velocity and acceleration ``limits``:
    the profile of ``toppra.algorithm.TOPPRA([JointVelocityConstraint, JointAccelerationConstraint], path,
    gridpoints=grid).compute_parameterization(0, 0)``, its stage programs solved in closed form in one numba call
    (:mod:`~maru_planner.planning.topp_kernel`; toppra's Seidel solver took ~2 µs a program from Python, ~0.25 ms a
    path); None where toppra fails.
    """
    x = _topp_kernel().rest_to_rest_nb(path(grid, 1), path(grid, 2), np.diff(grid), limits.velocity,
                                       limits.acceleration, toppra.constants.TINY, toppra.constants.MAX_TRIES)
    return np.sqrt(x) if len(x) else None


def _topp_kernel():
    """The toppra profile's kernels (:mod:`~maru_planner.planning.topp_kernel`), imported on first use."""
    # lazy: numba, loaded by warm_up before any request (planners on toy checkers that never blend skip it)
    from maru_planner.planning import topp_kernel

    return topp_kernel


def _within_limits(profile: _PathVelocity, limits: Limits) -> _PathVelocity:
    """``profile`` uniformly slowed down where toppra's discretisation let a limit be exceeded."""
    velocity_ratio, acceleration_ratio = profile.peak_ratios(limits)
    ratio = max(velocity_ratio, math.sqrt(acceleration_ratio))
    if ratio > 1.0:
        profile.sd = profile.sd / (ratio * (1.0 + RATIO_TOL))
    return profile


# --- ruckig -----------------------------------------------------------------------------------
@dataclass
class _RuckigPieces:
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


def _ruckig(waypoints, limits: Limits, check: _Check, max_deviation: float):
    report = TimingReport("ruckig")
    deviation = np.full(len(waypoints), max_deviation)
    deviation[[0, -1]] = 0.0
    for attempt in range(BLEND_RETRIES + 2):
        half = blend_half_lengths(waypoints, deviation)
        sections = [_ruckig_section(BlendedPath(w, h), limits) for w, h in _sections(waypoints, half)]
        failing = _failing_corners(sections, waypoints, half, max_deviation, check, limits, report)
        if not failing:
            break
        last = attempt >= BLEND_RETRIES
        for k in failing:
            report.fallbacks.append(f"ruckig blend at waypoint {k} not certified at deviation {deviation[k]:.3g} rad")
            deviation[k] = 0.0 if last else deviation[k] / BLEND_SHRINK
    else:
        raise _ParameterizationFailed(f"ruckig: no certified motion near waypoint(s) {failing}, even at rest there")
    _count_corners(waypoints, half, report)
    return [pieces for pieces, _ in sections], report


def _ruckig_section(path: BlendedPath, limits: Limits) -> tuple[_RuckigPieces, list[int]]:
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
    return _RuckigPieces(pieces, float(np.max(limits.velocity)), k), list(path.blend_of)


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
        raise _ParameterizationFailed(f"ruckig failed on piece {piece}: {exc}") from exc
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise _ParameterizationFailed(f"ruckig: {result} on piece {piece}")
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
    profile = _toppra_section(path, limits)
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


def _failing_corners(sections, waypoints, half, max_deviation, check: _Check, limits: Limits, report) -> list[int]:
    """Interior waypoints whose Ruckig motion leaves the path by more than allowed or collides there.

    A piece that stays on the path (a straight one) needs no check; one that leaves it is checked whole.
    """
    t0 = time.monotonic()
    failing = set()
    for pieces, blend_of in sections:
        for trajectory, corner in zip(pieces.trajectories, blend_of, strict=True):
            q, chords = _dense(trajectory, pieces, check.step, limits)
            off_path = deviation_from_path(q, waypoints)
            if off_path.max() <= 1e-9:
                continue
            report.certify_checks += len(q)
            if off_path.max() > max_deviation + 1e-9 or not check(q, chords):
                failing.add(int(corner) if corner >= 0 else _nearest_corner(q[off_path > 1e-9], waypoints))
    report.certify_time += time.monotonic() - t0
    return sorted(k for k in failing if 0 < k < len(waypoints) - 1)


def _nearest_corner(points: np.ndarray, waypoints: np.ndarray) -> int:
    """The interior waypoint closest to ``points`` (a straight piece overshooting past its end)."""
    if len(waypoints) < 3:
        return 0
    d = np.linalg.norm(waypoints[1:-1][None] - points[:, None], axis=2).min(axis=0)
    return int(np.argmin(d)) + 1


def _dense(trajectory, pieces: _RuckigPieces, step: float, limits: Limits) -> tuple[np.ndarray, np.ndarray]:
    """Positions along one of ``pieces``' Ruckig trajectories at most ``step`` apart in every joint, and per
    joint how far it can leave the chords between them (acceleration limit × interval² / 8)."""
    duration = trajectory.duration * pieces.time_scale  # real seconds
    n = max(2, math.ceil(duration * pieces.peak_speed / step) + 1)
    q = np.array([trajectory.at_time(t)[0] for t in np.linspace(0.0, trajectory.duration, n)])
    interval = duration / (n - 1)
    return q, limits.acceleration * interval * interval / 8.0


# --- sampling ---------------------------------------------------------------------------------
SAMPLE_CHUNK = 128  # points sampled between two looks at the deadline (a ruckig point: up to ~1 ms)


def _sample(sections, joint_names, end: np.ndarray, dt: float, max_points: int, deadline: float | None = None
            ) -> Trajectory:  # fmt: skip
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


def _state_in_chunks(section, t: np.ndarray, deadline: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    parts = []
    for first in range(0, len(t), SAMPLE_CHUNK):
        if deadline is not None and time.monotonic() > deadline:
            raise errors.PlanningTimedOut(f"the budget ran out while sampling {len(t)} trajectory points")
        parts.append(section.state(t[first : first + SAMPLE_CHUNK]))
    return tuple(np.concatenate([part[j] for part in parts]) for j in range(3))  # type: ignore[return-value]
