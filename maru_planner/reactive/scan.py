"""Laser scans to obstacle points (REP 117) and the paper's obstacle_check.

REP 117: a beam reading ``+inf`` means nothing within range, ``-inf`` too
close, NaN an invalid reading; readings outside ``[range_min, range_max]``
are not measurements. None of them becomes an obstacle point. A scan whose
readings are *all* NaN says nothing about the world (not even "free") and is
rejected, as are scans beyond the size and angle limits below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from maru_planner.errors import InvalidRequest

MAX_SCAN_BEAMS = 100_000  # ranges in one scan (real 2-D lasers have a few thousand)
MAX_SCAN_ANGLE = 2.0 * math.pi  # |angle_min|, |angle_max|, |angle_increment| (rad)


class ScanError(InvalidRequest):
    """A laser scan is malformed (length mismatch, NaN angles, zero increment...)."""

    source = "scan"


@dataclass
class LaserScanData:
    """A planar laser scan in the laser frame (fields as in sensor_msgs/LaserScan)."""

    angle_min: float
    angle_increment: float
    ranges: np.ndarray
    range_min: float
    range_max: float
    stamp: float = 0.0
    angle_max: float | None = None
    _angles: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        self.ranges = np.asarray(self.ranges, dtype=float).reshape(-1)
        self.validate()

    def validate(self) -> None:
        """Raise ScanError naming the bad field; accepts inf/NaN *ranges* (REP 117)."""
        for name in ("angle_min", "angle_increment", "range_min", "range_max"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ScanError(f"LaserScan.{name} is not finite ({value})")
        if self.angle_increment == 0.0:
            raise ScanError("LaserScan.angle_increment is 0")
        if self.range_min < 0.0 or self.range_max <= self.range_min:
            raise ScanError(f"LaserScan range limits invalid: range_min={self.range_min}, range_max={self.range_max}")
        check_scan_size(self.ranges.size)
        if np.all(np.isnan(self.ranges)):
            raise ScanError(f"LaserScan.ranges are all NaN ({self.ranges.size} invalid readings)")
        if self.angle_max is not None and not math.isfinite(float(self.angle_max)):
            raise ScanError(f"LaserScan.angle_max is not finite ({self.angle_max})")
        for name in ("angle_min", "angle_max", "angle_increment"):
            value = getattr(self, name)
            if value is not None and abs(float(value)) > MAX_SCAN_ANGLE:
                raise ScanError(f"LaserScan.{name} = {float(value):.4g} rad is beyond +-2 pi")
        if self.angle_max is not None:
            expected = int(round((self.angle_max - self.angle_min) / self.angle_increment)) + 1
            if abs(expected - self.ranges.size) > 1:
                raise ScanError(
                    f"LaserScan has {self.ranges.size} ranges but angle_min..angle_max / angle_increment "
                    f"gives {expected} beams"
                )

    @property
    def angles(self) -> np.ndarray:
        """Beam angles in the laser frame."""
        if self._angles is None or self._angles.size != self.ranges.size:
            self._angles = self.angle_min + self.angle_increment * np.arange(self.ranges.size)
        return self._angles


def check_scan_size(beams: int) -> None:
    """ScanError unless a scan of ``beams`` ranges is within 1..MAX_SCAN_BEAMS (checked before converting them)."""
    if beams == 0:
        raise ScanError("LaserScan.ranges is empty")
    if beams > MAX_SCAN_BEAMS:
        raise ScanError(f"LaserScan has {beams} ranges (at most {MAX_SCAN_BEAMS})")


def beam_mask(scan: LaserScanData, beam_window: tuple[int, int] | None = None) -> np.ndarray:
    """Beams that are real measurements (finite, within [range_min, range_max]) inside the window."""
    r = scan.ranges
    with np.errstate(invalid="ignore"):
        mask = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    if beam_window is not None:
        lo, hi = beam_window
        window = np.zeros(r.size, dtype=bool)
        window[max(lo, 0) : min(hi, r.size)] = True
        mask &= window
    return mask


def scan_to_points(
    scan: LaserScanData,
    laser_pose=(0.0, 0.0, 0.0),
    beam_window: tuple[int, int] | None = None,
    max_range: float | None = None,
) -> np.ndarray:
    """Obstacle points (m, 2) in the frame the laser is mounted on (``laser_pose`` = x, y, yaw in it)."""
    mask = beam_mask(scan, beam_window)
    if max_range is not None:
        mask &= scan.ranges <= max_range
    r = scan.ranges[mask]
    a = scan.angles[mask] + laser_pose[2]
    points = np.empty((r.size, 2))
    points[:, 0] = laser_pose[0] + r * np.cos(a)
    points[:, 1] = laser_pose[1] + r * np.sin(a)
    return points


def to_world(points: np.ndarray, pose) -> np.ndarray:
    """Robot-frame points (m, 2) to the world frame of ``pose`` = (x, y, theta)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    out = np.empty_like(points)
    out[:, 0] = pose[0] + c * points[:, 0] - s * points[:, 1]
    out[:, 1] = pose[1] + s * points[:, 0] + c * points[:, 1]
    return out


def obstacle_check(
    scan: LaserScanData, avoidance_range: float, beam_window: tuple[int, int] | None = None
) -> tuple[int, float] | None:
    """The paper's obstacle_check (Fig. 22): the first beam of the window closer than ``avoidance_range``.

    Returns (beam index, range) or None. Beams are scanned in index order,
    i.e. from the right (angle_min) to the left, as on the LMS200.
    """
    mask = beam_mask(scan, beam_window) & (scan.ranges < avoidance_range)
    hits = np.flatnonzero(mask)
    if hits.size == 0:
        return None
    return int(hits[0]), float(scan.ranges[hits[0]])
