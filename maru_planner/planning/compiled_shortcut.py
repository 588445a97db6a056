"""Moved to :mod:`maru_planner.planning.planners.compiled_shortcut` (its loop:
:mod:`maru_planner.planning.planners.kernels.shortcut`); this path is kept for existing imports."""

from maru_planner.planning.planners.compiled_shortcut import FIRST_TRIES, shortcut
from maru_planner.planning.planners.kernels.shortcut import STATE_FIELDS, run, untried_pairs

__all__ = ["FIRST_TRIES", "STATE_FIELDS", "run", "shortcut", "untried_pairs"]
