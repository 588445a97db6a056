"""The Jackal-like base: its response to /cmd_vel, the safety stops, odometry and contacts, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.physics.base_sim import BaseSim

EMPTY = np.zeros((30, 30), np.uint8)


def _drive(sim: BaseSim, v: float, w: float, seconds: float, period: float = 0.05) -> None:
    for _ in range(round(seconds / period)):
        sim.command(v, w)
        sim.advance(period)


@pytest.mark.parametrize("v, w", [(0.5, 0.0), (1.0, 0.0), (0.0, 1.0), (0.5, 1.0)])
def test_drive_follows_the_twist(v, w):
    sim = BaseSim(EMPTY)
    _drive(sim, v, w, 1.5)
    speed, yaw_rate = sim.true_twist()
    assert abs(speed - v) < 0.08
    assert abs(yaw_rate - w) < 0.25 * max(abs(w), 0.4)


def test_odometry_tracks_the_truth_and_drifts():
    sim = BaseSim(EMPTY, seed=2)
    _drive(sim, 0.8, 0.4, 3.0)
    x, y, yaw = sim.true_pose()
    x0, y0, yaw0 = sim.start
    travelled = math.hypot(x - x0, y - y0)
    odom = sim.odometry.pose
    assert abs(math.hypot(odom[0], odom[1]) - travelled) < 0.1 * travelled
    assert abs(math.remainder(odom[2] - (yaw - yaw0), math.tau)) < 0.1
    assert not np.isclose(odom[2], yaw - yaw0, atol=1e-6)  # a gyro with noise and bias: not the truth


def test_nan_command_stops_the_robot_and_is_counted():
    sim = BaseSim(EMPTY)
    _drive(sim, 1.0, 0.0, 1.0)
    _drive(sim, math.nan, 0.0, 1.0)
    assert abs(sim.true_twist()[0]) < 0.05
    assert sim.events.nan_commands == 20


def test_command_timeout_stops_the_robot_and_says_so():
    sim = BaseSim(EMPTY, cmd_timeout=0.5)
    _drive(sim, 1.0, 0.0, 1.0)
    assert sim.events.cmd_timeouts == 0
    sim.advance(1.5)  # the controller went quiet
    assert abs(sim.true_twist()[0]) < 0.05
    assert sim.events.cmd_timeouts == 1 and sim.events.first_timeout_s is not None


def test_driving_into_a_cylinder_is_a_contact():
    grid = EMPTY.copy()
    grid[15, 0:3] = 1  # cylinders ahead of the start (x = -2.175, y = 5.175 ..)
    sim = BaseSim(grid, start=(-2.175, 4.2, math.pi / 2))
    _drive(sim, 0.5, 0.0, 3.0)
    assert sim.collided and sim.events.contacts[0][0] < 3.0
    assert sim.clearance() < 0.02


def test_same_seed_same_run():
    runs = []
    for _ in range(2):
        sim = BaseSim(EMPTY, seed=7)
        _drive(sim, 0.7, 0.5, 1.0)
        assert sim.latest_scan is not None
        runs.append((sim.true_pose(), sim.odometry.pose.copy(), sim.latest_scan.ranges.copy()))
    assert runs[0][0] == runs[1][0]
    assert np.array_equal(runs[0][1], runs[1][1]) and np.array_equal(runs[0][2], runs[1][2])
