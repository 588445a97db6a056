"""The map the stack builds from its own scans (no prior map): an occupancy grid in the odometry frame.

Laser returns are counted per cell; a cell is an obstacle once ``min_hits`` returns fell in it (one
noisy return does not block a passage). Returns farther than ``max_range`` are not marked (odometry
drift smears far points). Unknown cells are free to the planner (the optimistic rule of Nav2's
``allow_unknown``). :meth:`clear` keeps only the latest scan (Nav2's clear-costmap recovery), for
when drift has closed every way to the goal.
"""

from __future__ import annotations

import math

import numpy as np

from maru_planner.base.grid import OccupancyGrid
from maru_planner.physics.laser import Scan


class OnlineMap:
    """A ``size`` (x, y metres) grid at ``resolution`` whose lower corner is ``origin`` (odom frame)."""

    def __init__(
        self,
        origin: tuple[float, float],
        size: tuple[float, float],
        resolution: float = 0.05,
        min_hits: int = 2,
        max_range: float = 6.0,
        laser_pose: tuple[float, float] = (0.0, 0.0),
    ):
        self.origin = (float(origin[0]), float(origin[1]))
        self.resolution = resolution
        self.min_hits = min_hits
        self.max_range = max_range
        self.laser_pose = laser_pose
        self.hits = np.zeros((round(size[1] / resolution), round(size[0] / resolution)), dtype=np.int32)
        self._last_points = np.zeros((0, 2))
        self._beams: tuple[tuple[float, float, int], np.ndarray, np.ndarray, np.ndarray] | None = None

    def _beam_angles(self, scan: Scan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The scan's beam angles and their cosines and sines (every scan of a run has the same beams)."""
        key = (scan.angle_min, scan.angle_increment, len(scan.ranges))
        if self._beams is None or self._beams[0] != key:
            angles = scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))
            self._beams = (key, angles, np.cos(angles), np.sin(angles))
        return self._beams[1], self._beams[2], self._beams[3]

    def scan_points(self, pose: np.ndarray, scan: Scan) -> np.ndarray:
        """The scan's returns within ``max_range`` as odom-frame (x, y)."""
        angles, cos0, sin0 = self._beam_angles(scan)
        ranges = scan.ranges
        keep = np.isfinite(ranges) & (ranges <= self.max_range) & (ranges >= scan.range_min)
        r = ranges[keep]
        x, y, yaw = float(pose[0]), float(pose[1]), float(pose[2])
        c, s = math.cos(yaw), math.sin(yaw)
        lx = x + c * self.laser_pose[0] - s * self.laser_pose[1]
        ly = y + s * self.laser_pose[0] + c * self.laser_pose[1]
        if yaw == 0.0:  # the robot's own frame (the safety check's points): the beams' cosines as they are
            return np.column_stack([lx + r * cos0[keep], ly + r * sin0[keep]])
        a = yaw + angles[keep]
        return np.column_stack([lx + r * np.cos(a), ly + r * np.sin(a)])

    def add_scan(self, pose: np.ndarray, scan: Scan) -> None:
        points = self.scan_points(pose, scan)
        self._last_points = points
        rows, cols, inside = self._cells(points)
        np.add.at(self.hits, (rows[inside], cols[inside]), 1)

    def clear(self, keep_near: tuple[float, float] | None = None, keep_radius: float = 1.0) -> None:
        """Forget everything but the latest scan and what lies within ``keep_radius`` of ``keep_near``
        (the laser does not see behind the robot: what it saw there stays)."""
        keep = np.zeros_like(self.hits)
        if keep_near is not None:
            ys = self.origin[1] + (np.arange(self.hits.shape[0]) + 0.5) * self.resolution - keep_near[1]
            xs = self.origin[0] + (np.arange(self.hits.shape[1]) + 0.5) * self.resolution - keep_near[0]
            near = ys[:, None] ** 2 + xs[None, :] ** 2 <= keep_radius**2
            keep[near] = self.hits[near]
        self.hits = keep
        rows, cols, inside = self._cells(self._last_points)
        self.hits[rows[inside], cols[inside]] = np.maximum(self.hits[rows[inside], cols[inside]], self.min_hits)

    def _cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        cols = np.floor((points[:, 0] - self.origin[0]) / self.resolution).astype(int)
        rows = np.floor((points[:, 1] - self.origin[1]) / self.resolution).astype(int)
        inside = (rows >= 0) & (rows < self.hits.shape[0]) & (cols >= 0) & (cols < self.hits.shape[1])
        return rows, cols, inside

    def near_obstacles(self, pose: np.ndarray, radius: float) -> np.ndarray:
        """Centres of occupied cells within ``radius`` of ``pose``, in the frame of ``pose`` (what the laser's
        blind sector behind the robot hides is still here)."""
        x, y, yaw = float(pose[0]), float(pose[1]), float(pose[2])
        row_lo, col_lo, _ = self._cells(np.array([[x - radius, y - radius]]))
        row_hi, col_hi, _ = self._cells(np.array([[x + radius, y + radius]]))
        rows = slice(max(int(row_lo[0]), 0), max(int(row_hi[0]) + 1, 0))
        cols = slice(max(int(col_lo[0]), 0), max(int(col_hi[0]) + 1, 0))
        cells = np.argwhere(self.hits[rows, cols] >= self.min_hits)
        if len(cells) == 0:
            return np.zeros((0, 2))
        px = self.origin[0] + (cells[:, 1] + cols.start + 0.5) * self.resolution - x
        py = self.origin[1] + (cells[:, 0] + rows.start + 0.5) * self.resolution - y
        c, s = math.cos(yaw), math.sin(yaw)
        return np.column_stack([c * px + s * py, -s * px + c * py])

    @property
    def occupied(self) -> np.ndarray:
        return self.hits >= self.min_hits

    def grid(self) -> OccupancyGrid:
        return OccupancyGrid(self.occupied, self.resolution, (*self.origin, 0.0), frame_id="odom")
