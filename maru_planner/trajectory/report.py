"""What a time parameterisation reports, and the failure that makes it fall back to trapezoids."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


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


class ParameterizationFailed(Exception):
    """toppra or Ruckig could not parameterise a section (numerical failure): fall back to trapezoids."""
