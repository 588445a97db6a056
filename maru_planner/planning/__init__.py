"""Arm motion planning: the ``MotionPlanner`` facade over a pipeline of stages (``pipeline``, ``stages/``), the
request adapters that build a ``PlanningProblem`` (``adapters``, ``problem``), and the planner registry
(:data:`PLANNERS`, ``planners/``: RRT, RRTConnect, PRM, GoalBiasedRRT, our RC-RRT, CompiledRRTConnect, CBiRRT and
whatever else is registered). No ROS here."""

from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.planners.registry import PLANNERS, ArmPlannerSpec, get_spec, planner_ids, register
from maru_planner.planning.problem import PlanningProblem
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
    "PlanningProblem",
    "PlannerConfig",
    "Trajectory",
    "get_spec",
    "planner_ids",
    "register",
]
