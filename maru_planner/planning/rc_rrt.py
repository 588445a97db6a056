"""Moved to :mod:`maru_planner.planning.planners.rc_rrt`; this path is kept for existing imports."""

from maru_planner.planning.planners.rc_rrt import (
    COMPILED_CAPACITY,
    RCRRT,
    RCRRT_PARAMS,
)

__all__ = [
    "RCRRT_PARAMS",
    "COMPILED_CAPACITY",
    "RCRRT",
]
