"""Scan -> obstacle points (REP 117) and the paper's obstacle_check."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.reactive import LaserScanData, ScanError, obstacle_check, scan_to_points, to_world
from maru_planner.reactive.scan import beam_mask


def lms200(ranges) -> LaserScanData:
    return LaserScanData(-math.pi / 2, math.radians(0.5), np.asarray(ranges, float), 0.05, 10.0)


def test_invalid_beams_are_ignored():
    r = np.full(361, 3.0)
    r[0], r[1], r[2], r[3], r[4] = np.inf, -np.inf, np.nan, 0.01, 12.0  # none is a measurement
    pts = scan_to_points(lms200(r))
    assert len(pts) == 356
    assert np.all(np.isfinite(pts))
    assert np.allclose(np.hypot(*pts.T), 3.0)


def test_beam_geometry_and_laser_offset():
    r = np.full(361, np.inf)
    r[180] = 2.0  # straight ahead
    r[360] = 1.0  # +90 deg (left)
    pts = scan_to_points(lms200(r), laser_pose=(0.2, 0.0, 0.0))
    assert pts == pytest.approx(np.array([[2.2, 0.0], [0.2, 1.0]]), abs=1e-9)


def test_window_keeps_only_central_beams():
    r = np.full(361, 2.0)
    mask = beam_mask(lms200(r), (31, 331))
    assert mask.sum() == 300 and not mask[30] and mask[31] and mask[330] and not mask[331]
    pts = scan_to_points(lms200(r), beam_window=(31, 331))
    angles = np.degrees(np.arctan2(pts[:, 1], pts[:, 0]))
    assert angles.min() == pytest.approx(-74.5) and angles.max() == pytest.approx(75.0)


def test_to_world_rotates_and_translates():
    pts = np.array([[1.0, 0.0], [0.0, 2.0]])
    out = to_world(pts, (1.0, -1.0, math.pi / 2))
    assert out == pytest.approx(np.array([[1.0, 0.0], [-1.0, -1.0]]))


def test_obstacle_check_reports_first_beam_in_index_order():
    r = np.full(361, 8.0)
    r[100], r[200], r[20] = 1.0, 0.5, 0.3  # beam 20 is outside the window
    assert obstacle_check(lms200(r), 1.5, (31, 331)) == (100, 1.0)
    assert obstacle_check(lms200(np.full(361, 8.0)), 1.5, (31, 331)) is None


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(angle_increment=0.0), "angle_increment is 0"),
        (dict(angle_min=float("nan")), "angle_min"),
        (dict(angle_increment=float("inf")), "angle_increment"),
        (dict(range_max=0.01), "range limits"),
        (dict(ranges=np.zeros(0)), "empty"),
        (dict(angle_max=math.pi / 2, ranges=np.ones(100)), "100 ranges"),
        (dict(ranges=np.full(361, np.nan)), "all NaN"),
        (dict(range_min=5.0, range_max=1.0), "range limits"),
        (dict(angle_min=1e300), "beyond"),
        (dict(angle_increment=1e-300, angle_max=1e-3), "ranges but"),
        (dict(ranges=np.ones(200_001), angle_increment=1e-5), "at most"),
    ],
)
def test_malformed_scans_raise_scan_error(kwargs, match):
    base = dict(
        angle_min=-math.pi / 2, angle_increment=math.radians(0.5), ranges=np.ones(361), range_min=0.05, range_max=10.0
    )
    base.update(kwargs)
    with pytest.raises(ScanError, match=match):
        LaserScanData(**base)


def test_validate_catches_mutation_after_construction():
    scan = lms200(np.ones(361))
    scan.angle_increment = 0.0
    with pytest.raises(ScanError):
        scan.validate()
