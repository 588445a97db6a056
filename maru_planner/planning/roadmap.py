"""Moved to :mod:`maru_planner.planning.planners.roadmap`; this path is kept for existing imports."""

from maru_planner.planning.planners.roadmap import (
    GROWTH_CHUNK,
    RevalidationReport,
    Roadmap,
)

__all__ = [
    "GROWTH_CHUNK",
    "RevalidationReport",
    "Roadmap",
]
