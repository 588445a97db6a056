"""Moved to :mod:`maru_planner.planning.planners.compiled_shortcut`; this path is kept for existing imports."""

from maru_planner.planning.planners.compiled_shortcut import FIRST_TRIES, shortcut

__all__ = ["FIRST_TRIES", "shortcut"]
