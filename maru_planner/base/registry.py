"""Base planner ids -> factories; ``plan(planner_id, grid, start, goal, footprint, **params)``.

Each entry is ``factory(footprint, **params) -> object with .plan(grid, start, goal) -> BasePlanResult``.
Adding a planner is one line in ``PLANNERS`` (helper-8: tunnel, biped_track, biped_wall).
"""

from __future__ import annotations

from maru_planner.base.astar import GridAStarPlanner
from maru_planner.base.biped.planners import biped_track, biped_wall
from maru_planner.base.mspp import MultiStagePlanner
from maru_planner.base.result import BasePlanResult
from maru_planner.base.se2 import SE2AStarPlanner
from maru_planner.base.tunnel import TunnelGridPlanner
from maru_planner.errors import InvalidPlanner, InvalidRequest


def _mspp_local(footprint, **params):
    return MultiStagePlanner(footprint, local=True, **params)


PLANNERS = {
    "astar": GridAStarPlanner,
    "se2": SE2AStarPlanner,
    "mspp": MultiStagePlanner,
    "mspp_local": _mspp_local,
    "tunnel": TunnelGridPlanner,  # paper 003
    "biped_track": biped_track,  # paper 004 (param world = 3-D world YAML)
    "biped_wall": biped_wall,
}

DEFAULT_PLANNER = "mspp"


def planner_ids() -> list[str]:
    return sorted(PLANNERS)


def make_planner(planner_id: str, footprint, **params):
    """Build a planner; InvalidPlanner for an unknown id, InvalidRequest for bad parameters."""
    factory = PLANNERS.get(planner_id or DEFAULT_PLANNER)
    if factory is None:
        raise InvalidPlanner(f"unknown base planner {planner_id!r}; known: {', '.join(planner_ids())}")
    try:
        return factory(footprint, **params)
    except (TypeError, ValueError) as exc:
        raise InvalidRequest(f"planner {planner_id!r}: {exc}") from exc


def plan(planner_id: str, grid, start, goal, footprint, **params) -> BasePlanResult:
    """Plan with the named planner (see ``PLANNERS``)."""
    return make_planner(planner_id, footprint, **params).plan(grid, start, goal)
