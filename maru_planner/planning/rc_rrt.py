"""Moved to :mod:`maru_planner.planning.planners.rc_rrt`; this path is kept for existing imports."""

from maru_planner.planning.planners.rc_rrt import (
    RCRRT_PARAMS,
    COMPILED_CAPACITY,
    RCRRT,
)

__all__ = [
    "RCRRT_PARAMS",
    "COMPILED_CAPACITY",
    "RCRRT",
]
