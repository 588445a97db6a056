"""Moved to :mod:`maru_planner.runtime.process_pool`; this path keeps working."""

from maru_planner.runtime.process_pool import START_METHOD, START_METHODS, STOP_TIMEOUT, ProcessPool
from maru_planner.runtime.robot_loading import RobotSource

__all__ = ["START_METHOD", "START_METHODS", "STOP_TIMEOUT", "ProcessPool", "RobotSource"]
