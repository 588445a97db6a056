"""``toppra``: the time-optimal path velocity along the blended curve (TOPP-RA).

The path speed is computed under ``velocity × scaling`` and ``acceleration × scaling``, with constant path
acceleration between grid points, which include every blend boundary (:meth:`BlendedPath.grid`). The result is then
evaluated on a dense grid and, if toppra's discretisation let a limit be exceeded, uniformly slowed down until every
limit holds at every sample it returns. A path of one straight segment skips the solver
(:func:`~maru_planner.trajectory.parameterize`): its time-optimal profile is the bang-coast-bang trapezoid of the
limiting joint, in closed form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import ModuleType

import numpy as np
import toppra.constants

from maru_planner.trajectory.blends import BlendedPath, sections
from maru_planner.trajectory.corners import certified_half_lengths
from maru_planner.trajectory.curves import Check, takes_pieces
from maru_planner.trajectory.limits import Limits
from maru_planner.trajectory.report import ParameterizationFailed, TimingReport

RATIO_TOL = 1e-9


@dataclass
class PathVelocity:
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
        (:func:`~maru_planner.trajectory.toppra_kernel.peak_ratios_nb`)."""
        path = self.path
        return _topp_kernel().peak_ratios_nb(self.grid, self.sd, self.pieces, path.starts, path.v0, path.dd,
                                             limits.velocity, limits.acceleration)  # fmt: skip


def toppra_sections(waypoints, limits: Limits, check: Check, max_deviation: float
                    ) -> tuple[list[PathVelocity], TimingReport]:  # fmt: skip
    """The toppra profile of each section between stops of ``waypoints``, its blends certified by ``check``."""
    report = TimingReport("toppra")
    half = certified_half_lengths(waypoints, max_deviation, check, report, takes_pieces(check.curve_free))
    report.corner_blends = half
    return [toppra_section(BlendedPath(w, h), limits) for w, h in sections(waypoints, half)], report


def toppra_section(path: BlendedPath, limits: Limits) -> PathVelocity:
    """toppra's rest-to-rest profile along ``path``, within ``limits`` at every point."""
    grid, pieces = path.grid()
    sd = rest_to_rest_speeds(path, grid, limits)
    if sd is None:
        raise ParameterizationFailed("toppra: the path is not controllable (numerical failure)")
    return _within_limits(PathVelocity(path, grid, pieces, sd), limits)


def rest_to_rest_speeds(path: BlendedPath, grid: np.ndarray, limits: Limits) -> np.ndarray | None:
    """Path speeds ṡ at the ``grid`` points from rest to rest under the joint velocity and acceleration ``limits``:
    the profile of ``toppra.algorithm.TOPPRA([JointVelocityConstraint, JointAccelerationConstraint], path,
    gridpoints=grid).compute_parameterization(0, 0)``, its stage programs solved in closed form in one numba call
    (:mod:`~maru_planner.trajectory.toppra_kernel`; toppra's Seidel solver took ~2 µs a program from Python, ~0.25 ms
    a path); None where toppra fails.
    """
    x = _topp_kernel().rest_to_rest_nb(
        path(grid, 1),
        path(grid, 2),
        np.diff(grid),
        limits.velocity,
        limits.acceleration,
        toppra.constants.TINY,
        toppra.constants.MAX_TRIES,
    )
    return np.sqrt(x) if len(x) else None


def _topp_kernel() -> ModuleType:
    """The toppra profile's kernels (:mod:`~maru_planner.trajectory.toppra_kernel`), imported on first use."""
    # lazy: numba, loaded by warm_up before any request (planners on toy checkers that never blend skip it)
    from maru_planner.trajectory import toppra_kernel

    return toppra_kernel


def _within_limits(profile: PathVelocity, limits: Limits) -> PathVelocity:
    """``profile`` uniformly slowed down where toppra's discretisation let a limit be exceeded."""
    velocity_ratio, acceleration_ratio = profile.peak_ratios(limits)
    ratio = max(velocity_ratio, math.sqrt(acceleration_ratio))
    if ratio > 1.0:
        profile.sd = profile.sd / (ratio * (1.0 + RATIO_TOL))
    return profile
