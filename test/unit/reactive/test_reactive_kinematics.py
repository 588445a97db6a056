"""Diff-drive kinematics (paper 001, eq. 1-9)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.reactive.kinematics import (
    DiffDriveParams,
    body_velocity,
    clamp_twist,
    integrate_unicycle,
    pose_rate,
    wheel_speeds,
    wrap_angle,
)

PARAMS = DiffDriveParams(wheel_radius=0.1, half_axle=0.25)


def test_straight_line_equal_wheel_rates():
    u, w = body_velocity(5.0, 5.0, PARAMS)
    assert u == pytest.approx(0.5) and w == pytest.approx(0.0)
    pose = integrate_unicycle((1.0, 2.0, math.pi / 2), u, w, 2.0)
    assert pose == pytest.approx((1.0, 3.0, math.pi / 2))


def test_turn_in_place_opposite_wheel_rates():
    u, w = body_velocity(2.5, -2.5, PARAMS)
    assert u == pytest.approx(0.0)
    assert w == pytest.approx(0.1 * 5.0 / 0.5)  # r (q_r - q_l) / 2l
    x, y, th = integrate_unicycle((0.3, -0.2, 0.0), u, w, math.pi / 2)
    assert (x, y) == pytest.approx((0.3, -0.2))
    assert th == pytest.approx(wrap_angle(math.pi / 2 * w))


def test_arc_follows_circle_of_radius_v_over_w():
    v, w = 0.5, 0.25  # radius 2 m, centre at (0, 2) from the origin facing +x
    for t in (1.0, 3.0, 6.0):
        x, y, th = integrate_unicycle((0.0, 0.0, 0.0), v, w, t)
        assert math.hypot(x, y - 2.0) == pytest.approx(2.0)
        assert th == pytest.approx(wrap_angle(w * t))
    # quarter circle ends at (2, 2) facing +y
    assert integrate_unicycle((0, 0, 0), v, w, (math.pi / 2) / w) == pytest.approx((2.0, 2.0, math.pi / 2))


def test_arc_matches_small_step_euler_of_eq_1_to_3():
    pose = np.array([0.0, 0.0, 0.3])
    qr, ql = 6.0, 4.0
    dt = 1e-4
    for _ in range(10000):
        pose = pose + dt * pose_rate(pose, qr, ql, PARAMS)
    u, w = body_velocity(qr, ql, PARAMS)
    exact = integrate_unicycle((0.0, 0.0, 0.3), u, w, 1.0)
    assert pose[:2] == pytest.approx(exact[:2], abs=1e-3)
    assert wrap_angle(pose[2]) == pytest.approx(exact[2], abs=1e-3)


def test_wheel_speeds_invert_body_velocity():
    for v, w in ((0.4, 0.0), (0.0, 1.2), (0.3, -0.7)):
        qr, ql = wheel_speeds(v, w, PARAMS)
        assert body_velocity(qr, ql, PARAMS) == pytest.approx((v, w))


def test_clamp_twist_keeps_curvature_and_limits():
    v, w = clamp_twist(1.0, 2.0, 0.5, 1.0)
    assert abs(v) <= 0.5 + 1e-12 and abs(w) <= 1.0 + 1e-12
    assert w / v == pytest.approx(2.0)


def test_bad_params_rejected():
    with pytest.raises(ValueError, match="wheel_radius"):
        DiffDriveParams(wheel_radius=0.0)
