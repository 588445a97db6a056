"""Moved to :mod:`maru_planner.planning.planners.planner_params`; this path is kept for existing imports."""

from maru_planner.planning.planners.planner_params import (
    PlannerParams,
    ompl_params,
    stored_params,
)

__all__ = [
    "PlannerParams",
    "stored_params",
    "ompl_params",
]
