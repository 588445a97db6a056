"""Arm motion planning on OMPL: state spaces from planning groups, batched edge checks, the planner
registry (:data:`PLANNERS`: RRT, RRTConnect, PRM, GoalBiasedRRT, our RC-RRT and whatever else is
registered), post-processing and the ``MotionPlanner`` facade. No ROS here."""

from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.planners.registry import PLANNERS, ArmPlannerSpec, get_spec, planner_ids, register
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStats, PlanStatus
from maru_planner.trajectory.trajectory import Trajectory

__all__ = [
    "PLANNERS",
    "ArmPlannerSpec",
    "MotionPlanner",
    "MotionRequest",
    "MotionResult",
    "PlanStats",
    "PlanStatus",
    "PlannerConfig",
    "Trajectory",
    "get_spec",
    "planner_ids",
    "register",
]
