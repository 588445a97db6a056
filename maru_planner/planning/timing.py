"""Old home of the time parameterisation: it lives in :mod:`maru_planner.trajectory` now (re-exported here)."""

from maru_planner.trajectory.blends import (
    BLEND_BEND_PARTS,
    BLEND_INTERVALS,
    GRID_INTERVALS,
    MIN_BLEND_SPEED,
    SHARED_END,
    BlendedPath,
    blend_half_lengths,
    deviation_from_path,
    parabola_chords,
    parabola_parts,
)
from maru_planner.trajectory.corners import BLEND_RETRIES, BLEND_SHRINK
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
from maru_planner.trajectory.parameterize import TimingReport, parameterize
from maru_planner.trajectory.ruckig import RUCKIG_DURATION
from maru_planner.trajectory.sampling import SAMPLE_CHUNK
from maru_planner.trajectory.toppra import RATIO_TOL

__all__ = [
    "BLEND_BEND_PARTS",
    "BLEND_INTERVALS",
    "BLEND_RETRIES",
    "BLEND_SHRINK",
    "CERTIFY_STEP",
    "GRID_INTERVALS",
    "JERK_RAMP_TIME",
    "METHODS",
    "MIN_BLEND_SPEED",
    "MIN_SCALING",
    "RATIO_TOL",
    "RUCKIG_DURATION",
    "SAMPLE_CHUNK",
    "SHARED_END",
    "BlendedPath",
    "CertifiedCurve",
    "Curve",
    "CurveFree",
    "Limits",
    "TimingReport",
    "WatchedCurve",
    "blend_half_lengths",
    "certified_clearance",
    "certified_curve",
    "check_method",
    "check_scaling",
    "curves_free",
    "default_jerk_limits",
    "deviation_from_path",
    "parabola_chords",
    "parabola_parts",
    "parameterize",
    "takes_bends",
    "takes_pieces",
]
