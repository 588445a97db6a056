"""Moved to :mod:`maru_planner.planning.planners.cbirrt` (CBiRRT is a registered planner now); this path is kept
for existing imports."""

from maru_planner.planning.planners.cbirrt import CONNECT_DISTANCE, DESCRIPTION, INSET, PARAMS, PLANNER_ID, STEP

__all__ = ["CONNECT_DISTANCE", "DESCRIPTION", "INSET", "PARAMS", "PLANNER_ID", "STEP"]
