"""Time parameterisation (planning/timing.py): limits, endpoints, deviation, blend fallbacks, point cap."""

from __future__ import annotations

import numpy as np
import pytest
from planning_toys import BoxWorldChecker

from maru_planner import errors
from maru_planner.planning import timing

TOL = 1e-6
NAMES3 = ["a", "b", "c"]
ZIGZAG = np.array([[0.0, 0.0, 0.0], [1.0, 0.3, 0.1], [1.2, 1.3, -0.2], [2.2, 1.5, 0.4], [2.4, 0.2, 0.5]])
LIMITS3 = timing.Limits.scaled([1.0, 1.5, 2.0], [2.0, 3.0, 4.0])


def always_free(_states: np.ndarray) -> bool:
    return True


def never_off_path(path: np.ndarray):
    """A curve check rejecting anything farther than 1e-9 rad from ``path`` (every blend collides)."""

    def free(states: np.ndarray) -> bool:
        return bool(np.all(timing.deviation_from_path(states, path) <= 1e-9))

    return free


def assert_within_limits(traj, limits: timing.Limits, jerk: bool = False) -> None:
    """Limits checked from the samples alone: reported values and finite differences (mean value theorem)."""
    dt = np.diff(traj.times)[:, None]
    assert np.all(dt > 0)
    assert np.max(np.abs(traj.velocities) / limits.velocity) <= 1 + TOL
    assert np.max(np.abs(traj.accelerations) / limits.acceleration) <= 1 + TOL
    assert np.max(np.abs(np.diff(traj.positions, axis=0)) / dt / limits.velocity) <= 1 + TOL
    assert np.max(np.abs(np.diff(traj.velocities, axis=0)) / dt / limits.acceleration) <= 1 + TOL
    if jerk:
        assert np.max(np.abs(np.diff(traj.accelerations, axis=0)) / dt / limits.jerk) <= 1 + TOL


def assert_consistent(traj) -> None:
    """Velocities integrate to the positions (trapezoidal rule on a fine sampling)."""
    dt = np.diff(traj.times)[:, None]
    predicted = traj.positions[:-1] + 0.5 * (traj.velocities[1:] + traj.velocities[:-1]) * dt
    assert np.max(np.abs(predicted - traj.positions[1:])) < 1e-3


@pytest.mark.parametrize("method", timing.METHODS)
def test_every_method_respects_the_limits_and_hits_the_endpoints_exactly(method):
    traj, report = timing.parameterize(
        ZIGZAG, NAMES3, LIMITS3, method, curve_free=always_free, max_deviation=0.3, dt=0.005
    )
    assert report.method == method
    assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")
    assert_consistent(traj)
    assert np.array_equal(traj.positions[0], ZIGZAG[0]) and np.array_equal(traj.positions[-1], ZIGZAG[-1])
    assert np.all(traj.velocities[[0, -1]] == 0.0)
    assert traj.times[0] == 0.0 and traj.joint_names == NAMES3


@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_blends_stay_within_the_deviation_and_beat_the_trapezoids(method):
    trapezoid, _ = timing.parameterize(ZIGZAG, NAMES3, LIMITS3, "trapezoid", curve_free=always_free, dt=0.005)
    for max_deviation in (0.05, 0.3):
        traj, report = timing.parameterize(
            ZIGZAG, NAMES3, LIMITS3, method, curve_free=always_free, max_deviation=max_deviation, dt=0.005
        )
        assert report.blends == len(ZIGZAG) - 2 and report.stops == 0 and not report.fallbacks
        assert 0.0 < report.max_deviation <= max_deviation + 1e-12
        assert timing.deviation_from_path(traj.positions, ZIGZAG).max() <= max_deviation + 1e-9
        assert traj.duration < trapezoid.duration


def test_toppra_is_time_optimal_on_a_straight_line():
    line = np.array([[0.0, 0.0, 0.0], [2.0, 1.0, 0.5]])
    traj, _ = timing.parameterize(line, NAMES3, LIMITS3, "toppra", curve_free=always_free)
    # limiting joint a: 2 rad at 1 rad/s, 2 rad/s^2 -> 2/1 + 1/2 s (accelerate, cruise, brake)
    assert traj.duration == pytest.approx(2.5, rel=2e-2)
    assert traj.duration >= 2.5 - 1e-9


def test_a_colliding_blend_is_shrunk_then_the_motion_stops_at_that_corner():
    # a small obstacle where the middle of the full blend at corner 2 passes; a quarter-size blend misses it
    corner = ZIGZAG[2]
    turn = (ZIGZAG[3] - corner) / np.linalg.norm(ZIGZAG[3] - corner) - (corner - ZIGZAG[1]) / np.linalg.norm(
        corner - ZIGZAG[1]
    )
    middle = corner + 0.25 * timing.blend_half_length(ZIGZAG, 2, 0.3) * turn
    box = BoxWorldChecker([(middle[:2] - 0.02, middle[:2] + 0.02)])

    def free(states):
        return box.first_invalid(states) < 0

    assert free(np.vstack([np.linspace(a, b, 200) for a, b in zip(ZIGZAG[:-1], ZIGZAG[1:], strict=True)]))
    for method in ("toppra", "ruckig"):
        traj, report = timing.parameterize(ZIGZAG, NAMES3, LIMITS3, method, curve_free=free, max_deviation=0.3)
        assert any("waypoint 2" in reason for reason in report.fallbacks), report.fallbacks
        assert report.blends == 3 and report.stops == 0
        assert box.first_invalid(traj.positions) < 0
        assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")

        stopped, report = timing.parameterize(
            ZIGZAG, NAMES3, LIMITS3, method, curve_free=never_off_path(ZIGZAG), max_deviation=0.3
        )
        assert report.blends == 0 and report.stops == 3
        assert timing.deviation_from_path(stopped.positions, ZIGZAG).max() <= 1e-9
        assert_within_limits(stopped, LIMITS3, jerk=method == "ruckig")
        for q in ZIGZAG:  # every waypoint is reached (at rest)
            k = np.argmin(np.linalg.norm(stopped.positions - q, axis=1))
            assert np.linalg.norm(stopped.positions[k] - q) < 1e-9 and np.allclose(stopped.velocities[k], 0.0)


@pytest.mark.parametrize("method", timing.METHODS)
def test_tiny_velocity_scaling_stays_within_the_point_cap(method):
    limits = timing.Limits.scaled([1.0, 1.5, 2.0], [2.0, 3.0, 4.0], velocity_scaling=1e-4)
    traj, _ = timing.parameterize(ZIGZAG, NAMES3, limits, method, curve_free=always_free, max_points=500)
    assert len(traj.times) <= 500
    assert traj.duration > 1e4  # 1e-4 of the speed: the motion really is that slow
    assert_within_limits(traj, limits, jerk=method == "ruckig")
    assert np.array_equal(traj.positions[-1], ZIGZAG[-1])


def test_zero_deviation_means_rest_at_every_corner():
    traj, report = timing.parameterize(ZIGZAG, NAMES3, LIMITS3, "toppra", curve_free=always_free, max_deviation=0.0)
    assert report.blends == 0 and report.stops == 3
    assert timing.deviation_from_path(traj.positions, ZIGZAG).max() <= 1e-9


def test_repeated_and_collinear_waypoints_are_harmless():
    path = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]])
    for method in timing.METHODS:
        traj, _ = timing.parameterize(path, NAMES3, LIMITS3, method, curve_free=always_free)
        assert np.array_equal(traj.positions[-1], path[-1])
        assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")


def test_a_path_of_one_configuration_is_a_trajectory_of_zero_duration():
    traj, _ = timing.parameterize(ZIGZAG[:1], NAMES3, LIMITS3, "toppra", curve_free=always_free)
    assert traj.duration == 0.0 and np.array_equal(traj.positions[-1], ZIGZAG[0])


def test_bad_method_deviation_and_point_cap_raise_typed_errors():
    with pytest.raises(errors.InvalidRequest, match="time_parameterization"):
        timing.parameterize(ZIGZAG, NAMES3, LIMITS3, "fastest", curve_free=always_free)
    with pytest.raises(errors.InvalidRequest, match="deviation"):
        timing.parameterize(ZIGZAG, NAMES3, LIMITS3, "toppra", curve_free=always_free, max_deviation=float("nan"))
    with pytest.raises(errors.InvalidRequest, match="max_points"):
        timing.parameterize(ZIGZAG, NAMES3, LIMITS3, "toppra", curve_free=always_free, max_points=1)


def test_default_jerk_limits_reach_full_acceleration_in_the_ramp_time():
    assert np.allclose(timing.default_jerk_limits([4.0, 15.0]), [4.0 / timing.JERK_RAMP_TIME, 150.0])
    limits = timing.Limits.scaled([1.0], [4.0], 0.5, 0.25, jerk_scaling=0.1)
    assert np.allclose([limits.velocity[0], limits.acceleration[0], limits.jerk[0]], [0.5, 1.0, 4.0])


def test_deviation_from_path_is_the_distance_to_the_nearest_segment():
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    points = np.array([[0.5, 0.2], [1.3, 0.5], [2.0, 2.0], [1.0, 0.0]])
    assert np.allclose(timing.deviation_from_path(points, path), [0.2, 0.3, np.sqrt(2.0), 0.0])
