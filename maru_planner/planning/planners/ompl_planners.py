"""OMPL's own planners in the registry: RRT, RRTConnect, PRM (roadmap kept between queries) and GoalBiasedRRT, their
parameters set through OMPL's parameter mechanism under OMPL's own names (:mod:`.planner_params`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ompl import base as ob
from ompl import geometric as og

from maru_planner.params import ParamSpec
from maru_planner.planning.planners.planner_params import MAX_JOINT_DISTANCE, MAX_NEIGHBOURS, ompl_params
from maru_planner.planning.planners.registry import ArmPlanner, ArmPlannerSpec, register
from maru_planner.planning.space import EdgeChecker

_RANGE = ParamSpec(
    "range",
    0.0,
    "max edge length (rad); 0 = OMPL's automatic 20 % of the space extent",
    lower=0.0,
    upper=MAX_JOINT_DISTANCE,
)


def _goal_bias(default: float) -> ParamSpec:
    return ParamSpec("goal_bias", default, "probability of sampling the goal", lower=0.0, upper=1.0)


def _ompl_factory(cls: type, name: str, accessors: Mapping[str, tuple[str, str]], specs: Mapping[str, ParamSpec]):
    """A factory building OMPL planner ``cls`` named ``name``, its parameters set by OMPL's declared names."""

    def build(si: ob.SpaceInformation, params: dict[str, Any], _edge_checker: EdgeChecker | None) -> ArmPlanner:
        planner = cls(si)
        planner.setName(name)
        ompl_params(planner, specs, accessors).set_params(params)
        return planner

    return build


def _register_ompl(planner_id: str, description: str, cls: type, specs: tuple[ParamSpec, ...],
                   accessors: Mapping[str, tuple[str, str]], capabilities: frozenset[str]) -> None:  # fmt: skip
    by_name = {spec.name: spec for spec in specs}
    register(ArmPlannerSpec(planner_id, description, _ompl_factory(cls, planner_id, accessors, by_name), by_name,
                            capabilities))  # fmt: skip


_RRT_ACCESSORS = {"range": ("setRange", "getRange"), "goal_bias": ("setGoalBias", "getGoalBias")}
_register_ompl("RRT", "OMPL RRT without goal bias", og.RRT, (_RANGE, _goal_bias(0.0)), _RRT_ACCESSORS,
               frozenset({"tree"}))  # fmt: skip
_register_ompl("RRTConnect", "OMPL RRTConnect: two trees grown toward each other", og.RRTConnect, (_RANGE,),
               {"range": ("setRange", "getRange")}, frozenset({"tree"}))  # fmt: skip
_register_ompl(
    "PRM",
    "OMPL PRM; the roadmap is kept between queries and re-validated after a scene change",
    og.PRM,
    (
        ParamSpec(
            "max_nearest_neighbors",
            3,
            "milestones each new milestone tries to connect to (OMPL: 10)",
            lower=1,
            upper=MAX_NEIGHBOURS,
        ),
    ),
    {"max_nearest_neighbors": ("setMaxNearestNeighbors", "getMaxNearestNeighbors")},
    frozenset({"roadmap"}),
)
_register_ompl("GoalBiasedRRT", "OMPL RRT sampling the goal with probability goal_bias", og.RRT,
               (_RANGE, _goal_bias(0.05)), _RRT_ACCESSORS, frozenset({"tree"}))  # fmt: skip
