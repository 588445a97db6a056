"""execution/interpolation.py equals joint_trajectory_controller's spline: linear with positions only, cubic with
velocities, quintic with accelerations (checked against scipy's Hermite polynomials through the same
end conditions, at random times), the segment from the state before the first point, the hold after the
last; bad points are typed errors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BPoly, CubicHermiteSpline

from maru_planner.errors import InvalidJointCount, InvalidJointNames, InvalidRequest, InvalidState
from maru_planner.execution.interpolation import SplineTrajectory, checked_points

RNG = np.random.default_rng(7)
TIMES = np.array([0.0, 0.4, 1.1, 1.5])
NAMES = ["a", "b"]
POS = RNG.uniform(-1, 1, (4, 2))
VEL = RNG.uniform(-2, 2, (4, 2))
ACC = RNG.uniform(-5, 5, (4, 2))
SAMPLE_TIMES = np.sort(RNG.uniform(0.0, TIMES[-1], 200))


def _reference(kind: str, joint: int):
    """scipy's piecewise polynomial through the same end conditions (degree 1, 3 or 5 per segment)."""
    if kind == "linear":
        return lambda t, nu=0: (
            np.interp(t, TIMES, POS[:, joint]) if nu == 0 else np.gradient(np.interp(t, TIMES, POS[:, joint]), t)
        )
    if kind == "cubic":
        return CubicHermiteSpline(TIMES, POS[:, joint], VEL[:, joint])
    return BPoly.from_derivatives(TIMES, np.stack([POS[:, joint], VEL[:, joint], ACC[:, joint]], axis=1))


@pytest.mark.parametrize("kind", ["linear", "cubic", "quintic"])
def test_segments_equal_the_spline_formula(kind):
    velocities = None if kind == "linear" else VEL
    accelerations = ACC if kind == "quintic" else None
    spline = SplineTrajectory(checked_points(NAMES, TIMES, POS, velocities, accelerations), POS[0])
    sample = spline.sample(SAMPLE_TIMES)
    for joint in range(2):
        reference = _reference(kind, joint)
        np.testing.assert_allclose(sample.positions[:, joint], reference(SAMPLE_TIMES), atol=1e-9)
        if kind != "linear":
            np.testing.assert_allclose(sample.velocities[:, joint], reference(SAMPLE_TIMES, 1), atol=1e-8)
            np.testing.assert_allclose(sample.accelerations[:, joint], reference(SAMPLE_TIMES, 2), atol=1e-7)
    if kind == "linear":  # constant velocity per segment, no acceleration (the controller's linear branch)
        slope = np.diff(POS, axis=0) / np.diff(TIMES)[:, None]
        segment = np.searchsorted(TIMES, SAMPLE_TIMES, side="right") - 1
        np.testing.assert_allclose(sample.velocities, slope[segment], atol=1e-12)
        assert not np.any(sample.accelerations)


def test_a_segment_is_linear_unless_both_ends_carry_velocities():
    velocities = VEL.copy()
    velocities[2] = np.nan  # point 2 carries none: segments 1-2 and 2-3 are linear, 0-1 cubic
    spline = SplineTrajectory(checked_points(NAMES, TIMES, POS, velocities), POS[0])
    t = np.array([0.2, 0.8, 1.3])
    sample = spline.sample(t)
    np.testing.assert_allclose(sample.positions[0], CubicHermiteSpline(TIMES[:2], POS[:2], VEL[:2])(0.2), atol=1e-12)
    for i, segment in ((1, 1), (2, 2)):
        expected = POS[segment] + (POS[segment + 1] - POS[segment]) * (t[i] - TIMES[segment]) / np.diff(TIMES)[segment]
        np.testing.assert_allclose(sample.positions[i], expected, atol=1e-12)


def test_before_the_first_point_starts_from_the_arm_state_and_after_the_last_holds():
    times = TIMES + 0.5  # the first point at 0.5 s
    before_p, before_v = np.array([0.3, -0.2]), np.array([0.1, 0.0])
    spline = SplineTrajectory(checked_points(NAMES, times, POS, VEL), before_p, before_v)
    lead = CubicHermiteSpline([0.0, 0.5], np.stack([before_p, POS[0]]), np.stack([before_v, VEL[0]]))
    np.testing.assert_allclose(spline.sample([0.0, 0.2]).positions, lead([0.0, 0.2]), atol=1e-12)
    after = spline.sample([times[-1], times[-1] + 3.0])
    np.testing.assert_allclose(after.positions, [POS[-1], POS[-1]])
    np.testing.assert_allclose(after.velocities, [VEL[-1], VEL[-1]])


@pytest.mark.parametrize(
    ("times", "positions", "velocities", "accelerations", "error", "match"),
    [
        ([0.0, 1.0, 1.0], np.zeros((3, 2)), None, None, InvalidRequest, "point 2: time_from_start 1 s does not"),
        ([0.0, 2.0, 1.0], np.zeros((3, 2)), None, None, InvalidRequest, "does not increase"),
        ([-1.0, 1.0], np.zeros((2, 2)), None, None, InvalidRequest, "negative"),
        ([0.0, np.nan], np.zeros((2, 2)), None, None, InvalidState, "point 1: time_from_start is NaN"),
        ([0.0, 1.0], [[0.0, 0.0], [np.nan, 0.0]], None, None, InvalidState, "point 1: positions of joint 0"),
        ([0.0, 1.0], [[0.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [np.inf, 1.0]], None, InvalidState, "velocities"),
        ([0.0, 1.0], np.zeros((2, 3)), None, None, InvalidJointCount, "2 points x 2 joints"),
        ([0.0, 1.0], np.zeros((2, 2)), None, np.zeros((2, 2)), InvalidRequest, "accelerations without velocities"),
        ([], np.zeros((0, 2)), None, None, InvalidRequest, "no points"),
    ],
)
def test_bad_points_are_typed_errors(times, positions, velocities, accelerations, error, match):
    with pytest.raises(error, match=match):
        checked_points(NAMES, times, positions, velocities, accelerations)


def test_bad_joint_names_are_typed_errors():
    with pytest.raises(InvalidJointNames, match="repeat"):
        checked_points(["a", "a"], [0.0], [[0.0, 0.0]])
    with pytest.raises(InvalidJointNames, match="non-empty"):
        checked_points(["a", ""], [0.0], [[0.0, 0.0]])
