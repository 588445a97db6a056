"""The UST-10-like laser (mj_multiRay) against known geometry."""

from __future__ import annotations

import math

import numpy as np

from maru_planner.physics.base_sim import BaseSim
from maru_planner.physics.laser import LaserSpec

SPEC = LaserSpec()


def _facing_side_wall(distance: float, seed: int = 0) -> BaseSim:
    """Robot facing +y with the laser level with a cylinder of the side wall x = -0.075 at ``distance`` m."""
    laser_y = 0.225 + 0.15 * 12
    start = (-0.15 - distance, laser_y - SPEC.x, math.pi / 2)
    return BaseSim(np.zeros((30, 30), np.uint8), seed=seed, start=start)


def test_laser_spec_is_the_ust10():
    assert SPEC.beams == 720 and math.isclose(SPEC.angle_max - SPEC.angle_min, math.radians(270), rel_tol=1e-5)
    assert (SPEC.range_min, SPEC.range_max, SPEC.rate, SPEC.noise) == (0.1, 30.0, 50.0, 0.001)


def test_wall_at_one_metre_reads_one_metre_within_the_noise():
    sim = _facing_side_wall(1.0)
    sim.advance(0.1)
    beam = int(np.argmin(np.abs(SPEC.angles() + math.pi / 2)))  # the beam pointing right (+x)
    readings = []
    for _ in range(20):
        sim.advance(1.0 / SPEC.rate)
        assert sim.latest_scan is not None
        readings.append(sim.latest_scan.ranges[beam])
    readings_arr = np.array(readings)
    assert abs(readings_arr.mean() - 1.0) < 0.003
    assert 0.0002 < readings_arr.std() < 0.003  # sd 1 mm noise, not exact


def test_nothing_in_a_direction_reads_inf_and_the_robot_is_not_seen():
    sim = _facing_side_wall(1.0)
    sim.advance(0.05)
    scan = sim.latest_scan
    assert scan is not None and len(scan.ranges) == 720
    ahead = int(np.argmin(np.abs(SPEC.angles())))
    assert np.isinf(scan.ranges[ahead])  # open field ahead: past the field, nothing
    finite = scan.ranges[np.isfinite(scan.ranges)]
    assert finite.min() > 0.5  # no return from the robot's own chassis or wheels
