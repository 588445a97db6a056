"""Planner registry: id → OMPL planner factory, with named parameters set through one function.

Ids: ``RRT`` (OMPL RRT, goal bias 0), ``GoalBiasedRRT`` (OMPL RRT with ``goal_bias``, default
0.05 = OMPL's own default), ``RRTConnect``, ``PRM`` (OMPL's, roadmap reused while the scene is
unchanged, see :mod:`maru_planner.planning.roadmap`) and ``RCRRT`` (ours,
:mod:`maru_planner.planning.rc_rrt`).

Parameter names (``PlannerConfig.planner_params[id]``):
RRT/GoalBiasedRRT/RRTConnect ``range`` (max edge length in rad, 0 = OMPL's automatic 20 % of
the space extent), RRT/GoalBiasedRRT ``goal_bias``, PRM ``max_nearest_neighbors`` (default 3, OMPL: 10; see docs),
RCRRT: ``step``, ``goal_bias``, ``candidates``, ``goal_range``, ``seed``.
"""

from __future__ import annotations

from ompl import geometric as og

from maru_planner.errors import InvalidPlanner, InvalidRequest
from maru_planner.planning.rc_rrt import PARAM_DEFAULTS as RCRRT_DEFAULTS
from maru_planner.planning.rc_rrt import RCRRT

PLANNER_IDS = ("RRT", "RRTConnect", "PRM", "GoalBiasedRRT", "RCRRT")

DEFAULT_PARAMS: dict[str, dict] = {
    "RRT": {"range": 0.0, "goal_bias": 0.0},
    "GoalBiasedRRT": {"range": 0.0, "goal_bias": 0.05},
    "RRTConnect": {"range": 0.0},
    "PRM": {"max_nearest_neighbors": 3},
    "RCRRT": dict(RCRRT_DEFAULTS),
}


def check_planner_id(planner_id: str) -> str:
    if planner_id not in PLANNER_IDS:
        raise InvalidPlanner(f"unknown planner {planner_id!r}; known: {', '.join(PLANNER_IDS)}")
    return planner_id


def merged_params(planner_id: str, overrides: dict | None) -> dict:
    """Default parameters of ``planner_id`` updated with ``overrides`` (unknown names rejected)."""
    params = dict(DEFAULT_PARAMS[check_planner_id(planner_id)])
    for name, value in (overrides or {}).items():
        if name not in params:
            raise InvalidRequest(
                f"planner {planner_id} has no parameter {name!r}; known: {', '.join(params)}", source="planner"
            )
        params[name] = value
    return params


def make_planner(planner_id: str, si, params: dict | None = None, edge_checker=None):
    """A configured planner instance for ``si``."""
    params = merged_params(planner_id, params)
    if planner_id in ("RRT", "GoalBiasedRRT"):
        planner = og.RRT(si)
        planner.setName(planner_id)
        planner.setRange(float(params["range"]))
        planner.setGoalBias(float(params["goal_bias"]))
    elif planner_id == "RRTConnect":
        planner = og.RRTConnect(si)
        planner.setRange(float(params["range"]))
    elif planner_id == "PRM":
        planner = og.PRM(si)
        planner.setMaxNearestNeighbors(int(params["max_nearest_neighbors"]))
    else:
        planner = RCRRT(si, edge_checker)
        for name, value in params.items():
            planner.set_param(name, value)
    return planner
