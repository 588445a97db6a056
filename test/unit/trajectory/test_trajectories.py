"""Time parameterisation (maru_planner/trajectory/): limits, endpoints, deviation, blend fallbacks, point cap."""

from __future__ import annotations

import time

import numpy as np
import pytest
import toppra.algorithm
import toppra.constraint
from planning_toys import BoxWorldChecker, ToyRobot, maze_checker

from maru_planner import errors
from maru_planner.collision.certify import chord_deviation
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.problems import PROBLEMS
from maru_planner.robot import RobotModel
from maru_planner.ros.planning_conversions import code_name, duration_seconds
from maru_planner.scene import Scene
from maru_planner.trajectory import (
    JERK_RAMP_TIME,
    METHODS,
    BlendedPath,
    Limits,
    blend_half_lengths,
    default_jerk_limits,
    deviation_from_path,
)
from maru_planner.trajectory import parameterize as parameterize_path
from maru_planner.trajectory import toppra as toppra_timing
from maru_planner.trajectory.blends import BLEND_BEND_PARTS, BLEND_INTERVALS, distinct, sections
from maru_planner.trajectory.toppra import rest_to_rest_speeds, toppra_section

TOL = 1e-6
NAMES3 = ["a", "b", "c"]
ZIGZAG = np.array([[0.0, 0.0, 0.0], [1.0, 0.3, 0.1], [1.2, 1.3, -0.2], [2.2, 1.5, 0.4], [2.4, 0.2, 0.5]])
LIMITS3 = Limits.scaled([1.0, 1.5, 2.0], [2.0, 3.0, 4.0])


def always_free(_states: np.ndarray, _deviation: np.ndarray) -> bool:
    return True


def parameterize(path, method, *, limits=LIMITS3, **options):
    """``trajectory.parameterize`` with the test's joint names, every curve free and a 0.3 rad deviation by default."""
    options.setdefault("curve_free", always_free)
    options.setdefault("max_deviation", 0.3)
    return parameterize_path(path, NAMES3[: np.shape(path)[1]], limits, method, **options)


def never_off_path(path: np.ndarray):
    """A curve check rejecting anything farther than 1e-9 rad from ``path`` (every blend collides)."""

    def free(states: np.ndarray, _deviation: np.ndarray) -> bool:
        return bool(np.all(deviation_from_path(states, path) <= 1e-9))

    return free


def assert_within_limits(traj, limits: Limits, jerk: bool = False) -> None:
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


@pytest.mark.parametrize("method", METHODS)
def test_every_method_respects_the_limits_and_hits_the_endpoints_exactly(method):
    traj, report = parameterize(ZIGZAG, method, max_deviation=0.3, dt=0.005)
    assert report.method == method
    assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")
    assert_consistent(traj)
    assert np.array_equal(traj.positions[0], ZIGZAG[0]) and np.array_equal(traj.positions[-1], ZIGZAG[-1])
    assert np.all(traj.velocities[[0, -1]] == 0.0)
    assert traj.times[0] == 0.0 and traj.joint_names == NAMES3


@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_blends_stay_within_the_deviation_and_beat_the_trapezoids(method):
    trapezoid, _ = parameterize(ZIGZAG, "trapezoid", dt=0.005)
    for max_deviation in (0.05, 0.3):
        traj, report = parameterize(ZIGZAG, method, max_deviation=max_deviation, dt=0.005)
        assert report.blends == len(ZIGZAG) - 2 and report.stops == 0 and not report.fallbacks
        assert 0.0 < report.max_deviation <= max_deviation + 1e-12
        assert deviation_from_path(traj.positions, ZIGZAG).max() <= max_deviation + 1e-9
        assert traj.duration < trapezoid.duration


def test_toppra_is_time_optimal_on_a_straight_line():
    line = np.array([[0.0, 0.0, 0.0], [2.0, 1.0, 0.5]])
    traj, _ = parameterize(line, "toppra")
    # limiting joint a: 2 rad at 1 rad/s, 2 rad/s^2 -> 2/1 + 1/2 s (accelerate, cruise, brake)
    assert traj.duration == pytest.approx(2.5, rel=2e-2)
    assert traj.duration >= 2.5 - 1e-9


def test_a_colliding_blend_is_shrunk_then_the_motion_stops_at_that_corner():
    # a small obstacle where the middle of the full blend at corner 2 passes; a quarter-size blend misses it
    corner = ZIGZAG[2]
    turn = (ZIGZAG[3] - corner) / np.linalg.norm(ZIGZAG[3] - corner) - (corner - ZIGZAG[1]) / np.linalg.norm(
        corner - ZIGZAG[1]
    )
    middle = corner + 0.25 * blend_half_lengths(ZIGZAG, np.full(len(ZIGZAG), 0.3))[2] * turn
    box = BoxWorldChecker([(middle[:2] - 0.02, middle[:2] + 0.02)])

    def free(states, _deviation):
        return box.first_invalid(states) < 0

    assert box.first_invalid(np.vstack([np.linspace(a, b, 200) for a, b in zip(ZIGZAG[:-1], ZIGZAG[1:])])) < 0
    for method in ("toppra", "ruckig"):
        traj, report = parameterize(ZIGZAG, method, curve_free=free, max_deviation=0.3)
        assert any("waypoint 2" in reason for reason in report.fallbacks), report.fallbacks
        assert report.blends == 3 and report.stops == 0
        assert box.first_invalid(traj.positions) < 0
        assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")

        stopped, report = parameterize(ZIGZAG, method, curve_free=never_off_path(ZIGZAG), max_deviation=0.3)
        assert report.blends == 0 and report.stops == 3
        assert deviation_from_path(stopped.positions, ZIGZAG).max() <= 1e-9
        assert_within_limits(stopped, LIMITS3, jerk=method == "ruckig")
        for q in ZIGZAG:  # every waypoint is reached (at rest)
            k = np.argmin(np.linalg.norm(stopped.positions - q, axis=1))
            assert np.linalg.norm(stopped.positions[k] - q) < 1e-9 and np.allclose(stopped.velocities[k], 0.0)


@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_each_check_gets_states_within_the_step_and_a_bound_on_the_chord_error(method):
    calls = []

    def recording(states, deviation):
        calls.append((states, deviation))
        return True

    parameterize(ZIGZAG, method, curve_free=recording, certify_step=0.02)
    assert calls
    for states, deviation in calls:
        assert np.max(np.abs(np.diff(states, axis=0))) <= 0.02 + 1e-12
        # a chord between samples taken at equal steps is off the curve by |second difference| / 8 (parabola:
        # exactly, toppra's blends), at most acceleration limit x interval^2 / 8 (any curve within it, ruckig)
        chord_error = np.abs(np.diff(states, n=2, axis=0)).max(axis=0) / 8.0
        assert np.all(deviation >= chord_error - 1e-12)
        if method == "toppra":
            assert np.allclose(deviation, chord_error, rtol=1e-6, atol=1e-15)


class BendRecorder:
    """A curve check that takes bent segments (as the certifier's does) and records what it is given."""

    takes_bends = True

    def __init__(self):
        self.curves = []

    def __call__(self, states, deviation):
        return self.many([(states, deviation)])[0]

    def many(self, curves):
        self.curves += curves
        return [True] * len(curves)


def test_a_bend_taking_check_gets_each_blend_as_exact_parabola_parts():
    recorder = BendRecorder()
    deviation = 0.3
    parameterize(ZIGZAG, "toppra", curve_free=recorder, max_deviation=deviation)
    assert len(recorder.curves) == len(ZIGZAG) - 2  # every corner once: none failed
    tau = np.linspace(0.0, 1.0, 11)
    half_lengths = blend_half_lengths(ZIGZAG, np.full(len(ZIGZAG), deviation))
    for k, (ends, off_chord, bends) in enumerate(recorder.curves, start=1):
        parts = BLEND_BEND_PARTS
        assert len(ends) == parts + 1 and len(bends) == parts and not off_chord.any()
        half_length = half_lengths[k]
        blend = BlendedPath(ZIGZAG[k - 1 : k + 2], np.array([0.0, half_length, 0.0]))  # corner k alone
        s0, s1 = blend.starts[1], blend.starts[2]
        for j, (a, b, bend) in enumerate(zip(ends[:-1], ends[1:], bends, strict=True)):
            on_part = (1.0 - tau)[:, None] * a + tau[:, None] * b + (tau * tau - tau)[:, None] * bend
            sigma = s0 + (j + tau) * (s1 - s0) / parts
            assert np.allclose(on_part, blend.at(sigma, np.ones(len(sigma), dtype=int), 0), atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_tiny_velocity_scaling_stays_within_the_point_cap(method):
    limits = Limits.scaled([1.0, 1.5, 2.0], [2.0, 3.0, 4.0], velocity_scaling=1e-4)
    traj, _ = parameterize(ZIGZAG, method, limits=limits, max_points=500)
    assert len(traj.times) <= 500
    assert traj.duration > 1e4  # 1e-4 of the speed: the motion really is that slow
    assert_within_limits(traj, limits, jerk=method == "ruckig")
    assert np.array_equal(traj.positions[-1], ZIGZAG[-1])


@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_when_toppra_fails_numerically_the_trapezoids_are_used(method, monkeypatch):
    monkeypatch.setattr(toppra_timing, "rest_to_rest_speeds", lambda *args: None)
    traj, report = parameterize(ZIGZAG, method)
    assert report.method == "trapezoid" and report.fallbacks and "toppra" in report.fallbacks[0]
    assert_within_limits(traj, LIMITS3)
    assert np.array_equal(traj.positions[-1], ZIGZAG[-1])


@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_past_the_deadline_no_blend_is_certified_and_every_corner_stops(method):
    traj, report = parameterize(ZIGZAG, method, deadline=time.monotonic() - 1.0)
    assert report.method == method and report.blends == 0 and report.stops == 3
    assert deviation_from_path(traj.positions, ZIGZAG).max() <= 1e-9
    assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")


def test_zero_deviation_means_rest_at_every_corner():
    traj, report = parameterize(ZIGZAG, "toppra", max_deviation=0.0)
    assert report.blends == 0 and report.stops == 3
    assert deviation_from_path(traj.positions, ZIGZAG).max() <= 1e-9


def test_repeated_and_collinear_waypoints_are_harmless():
    path = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]])
    for method in METHODS:
        traj, _ = parameterize(path, method)
        assert np.array_equal(traj.positions[-1], path[-1])
        assert_within_limits(traj, LIMITS3, jerk=method == "ruckig")


class PieceRecorder(BendRecorder):
    """A bend-taking check that also takes the straight pieces (as the certifier's does); ``fails(curve, call)``
    says which curves of the ``call``-th check are not free."""

    takes_pieces = True

    def __init__(self, fails=lambda curve, call: False):
        super().__init__()
        self.fails, self.calls, self.proven = fails, 0, []

    def many(self, curves):
        free = [not self.fails(curve, self.calls) for curve in curves]
        self.calls += 1
        self.curves += curves
        self.proven += [curve[0] for curve, ok in zip(curves, free) if ok and len(curve[0]) == 2 and len(curve) == 2]
        return free


def final_straight_parts(path: np.ndarray, half: np.ndarray) -> list[np.ndarray]:
    """Each segment of ``path`` without the ends its blends (``half`` per waypoint) take, where any is left."""
    unit = np.diff(path, axis=0) / np.linalg.norm(np.diff(path, axis=0), axis=1)[:, None]
    parts = [np.stack([path[i] + half[i] * unit[i], path[i + 1] - half[i + 1] * unit[i]]) for i in range(len(unit))]
    return [part for part, u in zip(parts, unit) if (part[1] - part[0]) @ u > 1e-12]


def on_a_piece(part: np.ndarray, pieces: list[np.ndarray]) -> bool:
    """Whether both ends of ``part`` lie (within 1e-12) on one of the straight ``pieces``."""
    return any(deviation_from_path(part, piece).max() <= 1e-12 for piece in pieces)


def test_straight_pieces_proven_with_the_blends_certify_the_whole_curve():
    """A check that takes pieces gets, with the blends, the straight parts between them; when every straight part of
    the final curve lies on one it proved -- also after a blend was shrunk, or became a stop -- the report says the
    curve is certified; a piece that is not free leaves it to the path's certification."""
    recorder = PieceRecorder()
    _, report = parameterize(ZIGZAG, "toppra", curve_free=recorder)
    parts = final_straight_parts(ZIGZAG, report.corner_blends)
    assert report.curve_certified and recorder.calls == 1 and len(recorder.proven) == len(parts) == 3  # 1 of 4: blends
    assert all(on_a_piece(part, recorder.proven) for part in parts)

    def blend_at(corner: int):  # the blend curves of ``corner``: the bent ones that pass nearest to it
        return lambda curve, _call: len(curve) == 3 and deviation_from_path(ZIGZAG[corner], curve[0]).min() < 0.3

    for fails, stops in ((lambda curve, call: call == 0 and blend_at(2)(curve, call), 0), (blend_at(2), 1)):
        recorder = PieceRecorder(fails)
        _, report = parameterize(ZIGZAG, "toppra", curve_free=recorder)
        assert report.stops == stops and report.curve_certified and recorder.calls > 1
        assert all(on_a_piece(part, recorder.proven) for part in final_straight_parts(ZIGZAG, report.corner_blends))

    piece_fails = PieceRecorder(lambda curve, _call: len(curve) == 2 and len(curve[0]) == 2)
    _, report = parameterize(ZIGZAG, "toppra", curve_free=piece_fails)
    assert report.blends == 3 and not report.curve_certified
    assert not parameterize(ZIGZAG, "toppra", curve_free=BendRecorder())[1].curve_certified  # no pieces taken
    assert not parameterize(ZIGZAG, "ruckig", curve_free=PieceRecorder())[1].curve_certified


@pytest.mark.parametrize("method", METHODS)
def test_a_waypoint_barely_off_the_line_is_still_passed(method):
    """A waypoint 1e-7 rad off the line between its neighbours passes the angle test for collinear points, yet the
    trajectory must not cut it short: certification proves the path through it, not the line."""
    path = np.array([[0.0, 0.0, 0.0], [1.0, 1e-7, 0.0], [2.0, 0.0, 0.0]])
    traj, _ = parameterize(path, method, curve_free=never_off_path(path))
    assert deviation_from_path(traj.positions, path).max() <= 1e-9
    assert np.linalg.norm(traj.positions - path[1], axis=1).min() <= 1e-9
    on_line = np.array([[0.0, 0.0, 0.0], [1.0, 1e-13, 0.0], [2.0, 0.0, 0.0]])  # rounding off the line: left out
    assert len(distinct(on_line)) == 2


def test_toppra_reports_each_certified_blend_at_the_row_of_the_path_it_rounds():
    """``corner_blends`` lines up with the rows given (a repeated row, the ends and a stopped corner get 0), and the
    trajectory leaves the path only within that far of those corners."""
    path = np.insert(ZIGZAG, 2, ZIGZAG[1], axis=0)  # row 1 twice

    def corner_3_collides(states: np.ndarray, _deviation: np.ndarray) -> bool:
        return deviation_from_path(ZIGZAG[3], states).min() > 0.3  # a blend near ZIGZAG[3]

    traj, report = parameterize(path, "toppra", curve_free=corner_3_collides)
    blends = report.corner_blends
    assert len(blends) == len(path) and blends[[0, 2, 4, 5]].tolist() == [0.0] * 4 and blends[[1, 3]].min() > 0
    far = deviation_from_path(traj.positions, path) > 1e-9
    near_a_blend = np.zeros(len(traj.positions), dtype=bool)
    for row in (1, 3):
        near_a_blend |= np.linalg.norm(traj.positions - path[row], axis=1) <= blends[row] + 1e-9
    assert far.any() and not (far & ~near_a_blend).any()
    assert parameterize(path, "ruckig")[1].corner_blends is None
    assert parameterize(path, "trapezoid")[1].corner_blends is None


def test_a_path_of_one_configuration_is_a_trajectory_of_zero_duration():
    traj, _ = parameterize(ZIGZAG[:1], "toppra")
    assert traj.duration == 0.0 and np.array_equal(traj.positions[-1], ZIGZAG[0])


def test_bad_method_deviation_and_point_cap_raise_typed_errors():
    with pytest.raises(errors.InvalidRequest, match="time_parameterization"):
        parameterize(ZIGZAG, "fastest")
    with pytest.raises(errors.InvalidRequest, match="deviation"):
        parameterize(ZIGZAG, "toppra", max_deviation=float("nan"))
    with pytest.raises(errors.InvalidRequest, match="max_points"):
        parameterize(ZIGZAG, "toppra", max_points=1)


def test_default_jerk_limits_reach_full_acceleration_in_the_ramp_time():
    assert np.allclose(default_jerk_limits([4.0, 15.0]), [4.0 / JERK_RAMP_TIME, 150.0])
    limits = Limits.scaled([1.0], [4.0], 0.5, 0.25, jerk_scaling=0.1)
    assert np.allclose([limits.velocity[0], limits.acceleration[0], limits.jerk[0]], [0.5, 1.0, 4.0])


@pytest.mark.parametrize("seed", range(40))
def test_the_speeds_are_toppras_own(seed):
    """``rest_to_rest_speeds`` (toppra's stage programs in closed form) gives ``TOPPRA.compute_parameterization(0,
    0)``'s profile on blended random paths of 2 to 13 joints, some with a joint that never moves, under binding
    velocity limits (toppra rounds their bound on ṡ to single precision: ~1e-7 of the peak) or none."""
    rng = np.random.default_rng(seed)
    dof = int(rng.integers(2, 14))
    waypoints = np.cumsum(rng.uniform(-1.0, 1.0, (int(rng.integers(3, 9)), dof)) * rng.uniform(0.05, 2.0), axis=0)
    if seed % 3 == 0:
        waypoints[:, 0] = 0.25
    half = blend_half_lengths(waypoints, np.full(len(waypoints), 0.2))
    section = max(sections(waypoints, half), key=lambda s: len(s[0]))  # cut at reversals, as parameterize
    path = BlendedPath(*section)
    grid, _ = path.grid()
    binding = seed % 2 == 0
    velocity = rng.uniform(0.5, 3.0, dof) if binding else np.full(dof, 1e3)
    limits = Limits.scaled(velocity, rng.uniform(1.0, 10.0, dof))
    constraints = [toppra.constraint.JointVelocityConstraint(limits.velocity),
                   toppra.constraint.JointAccelerationConstraint(limits.acceleration)]  # fmt: skip
    _sdd, expected, _v = toppra.algorithm.TOPPRA(
        constraints, path, gridpoints=grid, solver_wrapper="seidel"
    ).compute_parameterization(0.0, 0.0)
    ours = rest_to_rest_speeds(path, grid, limits)
    assert expected is not None and ours is not None
    assert np.max(expected) > 0.1
    assert np.max(np.abs(ours - expected)) <= (2e-6 if binding else 1e-9) * np.max(expected)


def test_a_profiles_states_follow_its_path_and_speeds():
    """At the times the profile reaches its grid points, the sampled state is the path's point there, its velocity
    the path's slope times ṡ; between them the acceleration is the path's curvature times ṡ² plus slope times s̈."""
    path = BlendedPath(ZIGZAG, blend_half_lengths(ZIGZAG, np.full(len(ZIGZAG), 0.3)))
    limits = Limits.scaled(np.full(3, 1.5), np.full(3, 4.0))
    profile = toppra_section(path, limits)
    q, qd, _qdd = profile.state(profile.times[:-1])
    assert np.allclose(q, path(profile.grid[:-1]), atol=1e-9)
    assert np.allclose(qd, path(profile.grid[:-1], 1) * profile.sd[:-1, None], atol=1e-9)
    sdd = (profile.sd[1:] ** 2 - profile.sd[:-1] ** 2) / (2.0 * np.diff(profile.grid))
    middle = 0.5 * (profile.times[:-1] + profile.times[1:])
    tau = middle - profile.times[:-1]
    s = profile.grid[:-1] + profile.sd[:-1] * tau + 0.5 * sdd * tau**2
    speed = profile.sd[:-1] + sdd * tau
    expected = path.at(s, profile.pieces, 2) * speed[:, None] ** 2 + path.at(s, profile.pieces, 1) * sdd[:, None]
    assert np.allclose(profile.state(middle)[2], expected, atol=1e-9)
    velocity_ratio, acceleration_ratio = profile.peak_ratios(limits)
    dense = profile.state(np.linspace(0.0, profile.duration, 5001))
    assert np.max(np.abs(dense[1]) / limits.velocity) <= velocity_ratio + 1e-9
    assert np.max(np.abs(dense[2]) / limits.acceleration) <= acceleration_ratio + 1e-9
    assert velocity_ratio <= 1.0 + 1e-9 and acceleration_ratio <= 1.0 + 1e-9


@pytest.mark.parametrize("deviation", [0.05, 0.3, 10.0])  # 10 rad: blends take whole segments, no straight left
def test_the_blended_curve_is_continuous_and_its_grid_covers_every_piece(deviation):
    path = BlendedPath(ZIGZAG, blend_half_lengths(ZIGZAG, np.full(len(ZIGZAG), deviation)))
    assert np.array_equal(path.blend_of[path.blend_of >= 0], np.arange(1, len(ZIGZAG) - 1))  # each corner, in order
    ends = path(path.starts[1:-1] - 1e-12)  # the end of each piece is where the next one starts, in value and slope
    assert np.allclose(ends, path.p0[1:], atol=1e-9)
    assert np.allclose(path(path.starts[1:-1] - 1e-12, 1), path.v0[1:], atol=1e-9)
    assert np.allclose(path(path.starts[-1]), ZIGZAG[-1]) and np.allclose(path(0.0), ZIGZAG[0])
    grid, pieces = path.grid()
    assert np.all(np.diff(grid) > 0) and grid[0] == 0.0 and grid[-1] == path.starts[-1]
    assert set(path.starts.tolist()) <= set(grid.tolist())  # every piece boundary is a grid point
    per_piece = np.bincount(pieces, minlength=len(path.p0))
    assert np.all(per_piece[path.blend_of >= 0] >= BLEND_INTERVALS) and np.all(per_piece >= 1)
    assert np.all((grid[:-1] >= path.starts[pieces]) & (grid[:-1] < path.starts[pieces + 1]))


def test_deviation_from_path_is_the_distance_to_the_nearest_segment():
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    points = np.array([[0.5, 0.2], [1.3, 0.5], [2.0, 2.0], [1.0, 0.0]])
    assert np.allclose(deviation_from_path(points, path), [0.2, 0.3, np.sqrt(2.0), 0.0])


# --- through MotionPlanner.plan ----------------------------------------------------------------
def maze_planner(**config) -> MotionPlanner:
    config.setdefault("resolution", 0.01)
    return MotionPlanner(ToyRobot(2), maze_checker(), PlannerConfig(**config))


def maze_request(**kw) -> MotionRequest:
    return MotionRequest("all", start={"j0": 0.05, "j1": 0.05}, goal_joints={"j0": 0.95, "j1": 0.95},
                         planner_id="RRTConnect", time_budget=5.0, seed=3, **kw)  # fmt: skip


@pytest.mark.parametrize("method", METHODS)
def test_each_method_through_the_planner_gives_a_free_trajectory_within_the_limits(method):
    planner = maze_planner()
    result = planner.plan(maze_request(time_parameterization=method, velocity_scaling=0.5, jerk_scaling=0.5))
    assert result.success, result.message
    assert result.stats.time_parameterization == method and method in result.message
    traj = result.trajectory
    robot = planner.robot
    limits = Limits.scaled(robot.velocity_limits, robot.acceleration_limits, 0.5, 1.0, 0.5)
    assert_within_limits(traj, limits, jerk=method == "ruckig")
    assert np.array_equal(traj.positions[0], result.path[0]) and np.array_equal(traj.positions[-1], result.path[-1])
    assert maze_checker().first_invalid(traj.positions) < 0
    assert deviation_from_path(traj.positions, result.path).max() <= planner.config.blend_deviation + 1e-9


def test_the_planner_uses_its_configured_method_when_the_request_names_none():
    assert maze_planner().plan(maze_request()).stats.time_parameterization == "toppra"
    planner = maze_planner(time_parameterization="trapezoid")
    assert planner.plan(maze_request()).stats.time_parameterization == "trapezoid"


def test_the_planner_caps_the_points_of_a_very_slow_trajectory():
    planner = maze_planner(max_trajectory_points=300)
    result = planner.plan(maze_request(velocity_scaling=1e-4))
    assert result.success and len(result.trajectory.times) <= 300
    assert result.trajectory.duration > 1e3


@pytest.mark.parametrize(
    ("field", "value"), [("time_parameterization", "bang-bang"), ("jerk_scaling", 0.0), ("jerk_scaling", 2.0)]
)
def test_bad_time_parameterization_fields_are_invalid_requests(field, value):
    result = maze_planner().plan(maze_request(**{field: value}))
    assert result.status is PlanStatus.INVALID_REQUEST and field in result.message


# --- through planning_node (PlanMotion.time_parameterization) ------------------------------------
MARU13_JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
MARU1_JERK = float(default_jerk_limits([4.0])[0])  # every Maru-1 joint: 4 rad/s² -> 40 rad/s³


@pytest.fixture(scope="module")
def plan_motion(node_process, rclpy_session):
    """Send the paper's 13-DOF problem (seed 3, so always the same path) to a running planning_node."""
    from conftest import SpinningNode

    from maru_planner.paths import config_path
    from maru_planner.ros.planning_client import PlanningClient, plan_request

    args = ["--ros-args", "--params-file", str(config_path("planner.yaml"))]
    node = node_process("maru_planner.ros.planning_node", args)
    tester = SpinningNode("trajectory_tests")
    client = PlanningClient(node=tester.node)
    assert client.plan_client.wait_for_service(timeout_sec=120.0), node.log()
    client.wait_until_ready(timeout=120.0)
    problem = PROBLEMS["maru13"]

    def send(**fields):
        request = plan_request(problem.goal_dict(MARU13_JOINTS), start=problem.start_dict(MARU13_JOINTS),
                               planner_id="RRTConnect", time_budget=20.0, seed=3)  # fmt: skip
        for name, value in fields.items():
            setattr(request, name, value)
        return client.call(client.plan_client, request, 60.0)

    yield send
    tester.destroy()
    assert node.alive(), "planning_node died:\n" + node.log()


def _duration(response) -> float:
    return duration_seconds(response.trajectory.points[-1].time_from_start)


@pytest.mark.ros
def test_plan_motion_times_by_the_requested_method_and_defaults_to_toppra(plan_motion):
    from maru_planner_interfaces.msg import PlanningError

    default, trapezoid = plan_motion(), plan_motion(time_parameterization="trapezoid")
    ruckig_response = plan_motion(time_parameterization="ruckig", max_jerk_scaling_factor=0.5)
    for response in (default, trapezoid, ruckig_response):
        assert response.error.code == PlanningError.SUCCESS, code_name(response.error.code) + response.error.message
    assert _duration(default) < 0.9 * _duration(trapezoid)  # the same path (seed 3), blended corners
    points = ruckig_response.trajectory.points
    times = np.array([duration_seconds(p.time_from_start) for p in points])
    accelerations = np.array([p.accelerations for p in points])
    jerk = np.abs(np.diff(accelerations, axis=0)) / np.diff(times)[:, None]
    assert np.max(jerk) / (0.5 * MARU1_JERK) <= 1 + 1e-6

    bad = plan_motion(time_parameterization="bang-bang")
    assert bad.error.code == PlanningError.INVALID_REQUEST and "time_parameterization" in bad.error.message


@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_on_a_certifying_planner_the_returned_trajectory_itself_certifies(method):
    """Maru-1 6-DOF paper problem: the sampled trajectory, chords plus their error bound, is proven clear."""
    problem = PROBLEMS["maru6"]
    robot = RobotModel.maru1()
    planner = MotionPlanner.from_scene(robot, Scene.from_yaml(problem.scene_path), PlannerConfig())
    assert planner.certifier is not None
    names = robot.groups[problem.group]
    start = dict(robot.named_states.get("home", {})) | problem.start_dict(names)
    result = planner.plan(MotionRequest(problem.group, start=start, goal_joints=problem.goal_dict(names),
                                        planner_id="RRTConnect", seed=2, time_budget=30.0,
                                        time_parameterization=method))  # fmt: skip
    assert result.success and result.stats.time_parameterization == method, result.message
    traj = result.trajectory
    indices = robot.joint_indices(traj.joint_names)
    full = np.repeat(np.array([start.get(n, 0.0) for n in robot.joint_names])[None], len(traj.times), axis=0)
    full[:, indices] = traj.positions
    acceleration = np.zeros(robot.nq)
    acceleration[indices] = robot.acceleration_limits[indices]
    certificate = planner.certifier.certify_path(full, margin=0.0, deviation=chord_deviation(traj.times, acceleration))
    assert certificate.valid, certificate.reason


def test_one_straight_segment_is_timed_in_closed_form_as_toppra_would():
    """toppra on a single segment returns the trapezoid of the limiting joint: TOPP-RA's own optimum (its
    discretised profile may only be slower), with no blend to certify."""
    path = np.array([[0.0, 0.0, 0.0], [1.2, -0.4, 2.5]])
    trajectory, report = parameterize(path, "toppra")
    assert report.method == "toppra" and report.certify_checks == 0
    solver = toppra_section(BlendedPath(path, np.zeros(2)), LIMITS3)
    assert trajectory.duration <= solver.duration + 1e-9
    assert trajectory.duration == pytest.approx(solver.duration, rel=0.02)
    assert np.allclose(trajectory.positions[-1], path[-1])
