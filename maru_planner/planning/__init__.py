"""Arm motion planning on OMPL: state spaces from planning groups, batched edge checks, the planner
registry (RRT, RRTConnect, PRM, GoalBiasedRRT and our RC-RRT), post-processing and the
``MotionPlanner`` facade. No ROS here."""

from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.registry import PLANNER_IDS
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStats, PlanStatus, Trajectory

__all__ = [
    "PLANNER_IDS",
    "MotionPlanner",
    "MotionRequest",
    "MotionResult",
    "PlanStats",
    "PlanStatus",
    "PlannerConfig",
    "Trajectory",
]
