"""Reactive elastic-strip layer of paper 001 (no ROS): scan -> forces -> strip -> (v, w) + arm steps."""

from maru_planner.reactive.controller import ControlOutput, ElasticStripController, StripParams
from maru_planner.reactive.scan import LaserScanData, ScanError, obstacle_check, scan_to_points, to_world

__all__ = [
    "ControlOutput",
    "ElasticStripController",
    "LaserScanData",
    "ScanError",
    "StripParams",
    "obstacle_check",
    "scan_to_points",
    "to_world",
]
