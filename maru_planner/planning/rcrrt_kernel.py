"""Moved to :mod:`maru_planner.planning.planners.kernels.rcrrt`; this path is kept for existing imports."""

from maru_planner.planning.planners.kernels.rcrrt import (
    AWAITING_VERDICT,
    COLLISIONS,
    COUNT,
    EXHAUSTED,
    EXTEND,
    FROM,
    FULL,
    GOAL_BIAS,
    GOAL_EDGE,
    GOAL_NODE,
    GOAL_RANGE,
    INPUT,
    KIND,
    NEED_EXACT,
    NO_EDGE,
    PENDING,
    PROPOSED,
    RUNNING,
    SOLVED,
    STATE_FIELDS,
    STEP,
    Tree,
    rehash,
    run,
    settings,
    start,
)

__all__ = [
    "AWAITING_VERDICT", "COLLISIONS", "COUNT", "EXHAUSTED", "EXTEND", "FROM", "FULL", "GOAL_BIAS", "GOAL_EDGE",
    "GOAL_NODE", "GOAL_RANGE", "INPUT", "KIND", "NEED_EXACT", "NO_EDGE", "PENDING", "PROPOSED", "RUNNING", "SOLVED",
    "STATE_FIELDS", "STEP", "Tree", "rehash", "run", "settings", "start",
]  # fmt: skip
