"""The footprint check's swept clearance and the online map's scan points: the fast paths give what the
plain per-pose and per-beam arithmetic gives (bit for bit: a run must not change with them)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.barn.online_map import OnlineMap
from maru_planner.barn.safety import SafetyFilter
from maru_planner.physics.laser import LaserSpec, Scan


@pytest.mark.parametrize("v, w", [(0.8, 0.0), (1.2, 1.5), (-0.3, -0.8), (0.0, 2.0)])
def test_swept_clearance_is_the_smallest_clearance_along_the_arc(v, w):
    safety = SafetyFilter(0.254, 0.215)
    points = np.random.default_rng(4).uniform(-1.5, 1.5, (200, 2))
    x = y = th = 0.0
    dt, expected = safety.horizon / 6, math.inf
    for _ in range(6):
        x += v * math.cos(th + 0.5 * w * dt) * dt
        y += v * math.sin(th + 0.5 * w * dt) * dt
        th += w * dt
        expected = min(expected, safety.clearance(points, (x, y, th)))
    assert safety.swept_clearance(v, w, points) == expected
    assert safety.swept_clearance(v, w, np.zeros((0, 2))) == math.inf


def _scan(rng: np.random.Generator) -> Scan:
    spec = LaserSpec()
    ranges = rng.uniform(0.05, 9.0, spec.beams)
    ranges[::7] = np.inf
    return Scan(ranges, spec.angle_min, spec.angle_increment, spec.range_min, spec.range_max, 0.0)


@pytest.mark.parametrize("pose", [(0.0, 0.0, 0.0), (1.0, -0.5, 0.0), (2.0, 1.0, 0.7), (-1.0, 0.3, -2.9)])
def test_scan_points_are_each_beam_at_its_range_from_the_laser(pose):
    online = OnlineMap((-3.0, -3.5), (16.0, 7.0), laser_pose=(0.055, 0.0))
    scan = _scan(np.random.default_rng(1))
    for _ in range(2):  # the second time from the cached beam angles
        points = online.scan_points(np.array(pose), scan)
        angles = scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))
        keep = np.isfinite(scan.ranges) & (scan.ranges <= online.max_range) & (scan.ranges >= scan.range_min)
        x, y, yaw = pose
        lx, ly = x + 0.055 * math.cos(yaw), y + 0.055 * math.sin(yaw)
        expected = np.column_stack(
            [lx + scan.ranges[keep] * np.cos(yaw + angles[keep]), ly + scan.ranges[keep] * np.sin(yaw + angles[keep])]
        )
        np.testing.assert_allclose(points, expected, atol=1e-12)
