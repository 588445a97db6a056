"""Path -> timed trajectory (MoveIt's trajectory_processing): one module per method, one entry point.

:func:`parameterize` times a certified joint-space path by ``toppra`` (time-optimal, blended corners), ``ruckig``
(jerk-limited, blended corners) or ``trapezoid`` (rest at every waypoint), every blend re-checked by the caller's
curve check. No ROS here; below planning, above collision.
"""

from maru_planner.trajectory.blends import BlendedPath, blend_half_lengths, deviation_from_path, drop_collinear
from maru_planner.trajectory.curves import (
    CERTIFY_STEP,
    CertifiedCurve,
    Curve,
    CurveFree,
    WatchedCurve,
    certified_clearance,
    certified_curve,
    curves_free,
    takes_bends,
    takes_pieces,
)
from maru_planner.trajectory.limits import (
    JERK_RAMP_TIME,
    METHODS,
    MIN_SCALING,
    Limits,
    check_method,
    check_scaling,
    default_jerk_limits,
)
from maru_planner.trajectory.metrics import path_length, smoothness
from maru_planner.trajectory.parameterize import TimingReport, parameterize
from maru_planner.trajectory.trajectory import Trajectory
from maru_planner.trajectory.trapezoid import time_parameterize

__all__ = [
    "CERTIFY_STEP",
    "JERK_RAMP_TIME",
    "METHODS",
    "MIN_SCALING",
    "BlendedPath",
    "CertifiedCurve",
    "Curve",
    "CurveFree",
    "Limits",
    "TimingReport",
    "Trajectory",
    "WatchedCurve",
    "blend_half_lengths",
    "certified_clearance",
    "certified_curve",
    "check_method",
    "check_scaling",
    "curves_free",
    "default_jerk_limits",
    "deviation_from_path",
    "drop_collinear",
    "parameterize",
    "path_length",
    "smoothness",
    "takes_bends",
    "takes_pieces",
    "time_parameterize",
]
