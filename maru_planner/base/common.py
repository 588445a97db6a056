"""Path assembly shared by the grid planners: cells or SE(2) states -> map-frame (x, y, theta) rows."""

from __future__ import annotations

import math

import numpy as np

from maru_planner.base.grid import OccupancyGrid


def wrap_angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def interpolate_headings(xy: np.ndarray, theta0: float, theta1: float) -> np.ndarray:
    """Headings along a polyline, turning from theta0 to theta1 in proportion to arc length."""
    n = len(xy)
    if n == 1:
        return np.array([theta1])
    seg = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    frac = s / s[-1] if s[-1] > 0 else np.linspace(0.0, 1.0, n)
    return theta0 + wrap_angle(theta1 - theta0) * frac


def cells_to_path(grid: OccupancyGrid, cells: np.ndarray, theta0: float, theta1: float) -> np.ndarray:
    """(n, 2) cells -> (n, 3) map-frame (x, y, theta) at cell centres, heading interpolated."""
    xy = grid.cells_to_world(cells)
    return np.column_stack([xy, interpolate_headings(xy, theta0, theta1)])


def states_to_path(grid: OccupancyGrid, states: np.ndarray, headings: int) -> np.ndarray:
    """(n, 3) SE(2) states (k, row, col) -> (n, 3) map-frame (x, y, theta)."""
    xy = grid.cells_to_world(states[:, 1:3])
    theta = np.array([wrap_angle(2 * math.pi * k / headings + grid.origin[2]) for k in states[:, 0]])
    return np.column_stack([xy, theta])
