"""The in-process BARN stack end to end on an easy and a hard public world, and its pieces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.barn.online_map import OnlineMap
from maru_planner.barn.safety import SafetyFilter, StuckMonitor
from maru_planner.barn.stack import run_barn
from maru_planner.physics.barn_world import barn_dir, optimal_time, world_grid
from maru_planner.physics.laser import Scan

pytestmark = pytest.mark.skipif(not (barn_dir() / "grid_files").is_dir(), reason="BARN data not present")


@pytest.mark.parametrize("world", [0, 287])  # 0: easy, a gentle S; 287: hard, a swerve through dense clutter
def test_public_world_end_to_end(world):
    score, trace = run_barn(world_grid(world), optimal_time(world), seed=0, world_name=str(world))
    assert score.success and not score.collision and not score.timeout
    assert not trace.contacts and score.min_clearance_m > 0.0
    assert 0.125 <= score.metric <= 0.5
    assert score.time_s is not None and score.time_s < 30.0
    assert math.hypot(trace.trajectory[-1, 0] + 2.25, trace.trajectory[-1, 1] - 13.0) <= 1.0
    assert score.replans >= 2  # the path was re-planned as the map grew


def _scan(ranges: np.ndarray) -> Scan:
    return Scan(ranges, -math.pi / 2, math.pi / (len(ranges) - 1), 0.1, 30.0, 0.0)


def test_online_map_needs_two_returns_and_clear_keeps_the_surroundings():
    grid_map = OnlineMap((-1.0, -1.0), (4.0, 2.0), resolution=0.05)
    ranges = np.full(181, np.inf)
    ranges[90] = 1.0  # straight ahead
    grid_map.add_scan(np.zeros(3), _scan(ranges))
    assert not grid_map.occupied.any()
    grid_map.add_scan(np.zeros(3), _scan(ranges))
    assert grid_map.occupied.sum() == 1
    grid_map.clear(keep_near=(0.0, 0.0), keep_radius=1.5)
    assert grid_map.occupied.sum() == 1
    grid_map.clear(keep_near=(3.0, 0.0), keep_radius=0.5)  # the latest scan's point stays
    assert grid_map.occupied.sum() == 1
    assert len(grid_map.near_obstacles(np.array([0.0, 0.0, math.pi / 2]), 1.5)) == 1


def test_safety_filter_keeps_the_corners_off_obstacles():
    safety = SafetyFilter(0.254, 0.215, margin=0.03)
    ahead = np.array([[0.45, 0.0]])
    v, w, changed = safety.filter(1.0, 0.0, ahead)
    assert changed and v < 1.0
    behind_left = np.array([[-0.2, 0.27]])  # beside the rear-left corner: it swings into it turning right
    assert safety.is_safe(0.0, 0.0, behind_left)
    assert not safety.is_safe(0.0, -2.0, behind_left)
    assert safety.is_safe(0.0, 2.0, behind_left)
    assert safety.filter(0.5, 0.0, np.zeros((0, 2))) == (0.5, 0.0, False)


def test_stuck_monitor():
    monitor = StuckMonitor(window=2.0, distance=0.1)
    assert not any(monitor.update(t * 0.1, 0.01 * t, 0.0) for t in range(15))
    assert any(monitor.update(t * 0.1, 0.15, 0.0) for t in range(15, 40))
