"""Moved to :mod:`maru_planner.planning.planners.registry`; this path is kept for existing imports."""

from maru_planner.planning.planners.registry import (
    CAPABILITIES,
    PLANNERS,
    ArmPlanner,
    ArmPlannerSpec,
    PlannerFactory,
    ProvesFailure,
    ReportsGraphSize,
    RoadmapPlanner,
    get_spec,
    make_planner,
    merged_params,
    planner_ids,
    register,
)

__all__ = [
    "CAPABILITIES",
    "ArmPlanner",
    "ReportsGraphSize",
    "ProvesFailure",
    "RoadmapPlanner",
    "PlannerFactory",
    "ArmPlannerSpec",
    "PLANNERS",
    "register",
    "planner_ids",
    "get_spec",
    "merged_params",
    "make_planner",
]
