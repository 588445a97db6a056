"""Arm planner registry: one :class:`ArmPlannerSpec` per planner id.

A spec says how to build the planner on a ``SpaceInformation`` (``factory``), which parameters it
takes (:class:`~maru_planner.params.ParamSpec` s with defaults, ranges and descriptions) and what
it can do (``capabilities``). The :class:`~maru_planner.planning.MotionPlanner` facade, ``maru-plan``
(its ``--planner`` choices and ``--param``), the planning node (parameters ``planners.<ID>.<param>``)
and the parametrised tests all read :data:`PLANNERS`, so adding a planner is one :func:`register`
call (plus the planner's own file).

Built in (each registered by its own module, imported by ``planning/planners/__init__.py``): ``RRT`` (OMPL RRT,
goal bias 0), ``GoalBiasedRRT`` (OMPL RRT, goal bias 0.05 = OMPL's default), ``RRTConnect``, ``PRM`` (OMPL's, roadmap
kept between queries, see
:mod:`maru_planner.planning.planners.roadmap`), ``RCRRT`` (ours, :mod:`maru_planner.planning.planners.rc_rrt`) and
``CompiledRRTConnect`` (ours, numba on the sphere model, :mod:`maru_planner.planning.planners.compiled_rrtc`).
Parameters are set through OMPL's parameter mechanism under OMPL's own names
(:mod:`maru_planner.planning.planners.planner_params`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from ompl import base as ob

from maru_planner.errors import InvalidPlanner, InvalidRequest
from maru_planner.params import ParamSpec, check_params
from maru_planner.planning.space import EdgeChecker

if TYPE_CHECKING:
    from maru_planner.planning.problem import PlanningProblem
    from maru_planner.planning.types import PlanStats

#: What a planner can declare about itself (``ArmPlannerSpec.capabilities``).
CAPABILITIES: dict[str, str] = {
    "tree": "grows a search tree from the start for each query",
    "roadmap": "keeps a roadmap between queries while the scene is unchanged (the factory returns a RoadmapPlanner)",
    "anytime": "keeps improving its solution until the search time ends",
    "resolution_complete": "proves that no path exists at its resolution (failure_proof)",
    "path_constraints": "keeps a request's path constraints along the whole motion",
}


class ArmPlanner(Protocol):
    """What the facade calls on a planner: OMPL's ``ompl.base.Planner`` surface."""

    def getName(self) -> str: ...  # noqa: N802 (OMPL's names)

    def setup(self) -> None: ...

    def solve(self, ptc: ob.PlannerTerminationCondition) -> ob.PlannerStatus: ...

    def clear(self) -> None: ...

    def getPlannerData(self, data: ob.PlannerData) -> None: ...  # noqa: N802


@runtime_checkable
class ReportsGraphSize(Protocol):
    """Optional hook: a planner that counts its own nodes and edges (no PlannerData copy needed)."""

    def graph_size(self) -> tuple[int, int]: ...


@runtime_checkable
class ProvesFailure(Protocol):
    """Optional hook: after a failed solve, the reason no path exists (None if it only ran out of time)."""

    def failure_proof(self) -> str | None: ...


class RoadmapPlanner(ArmPlanner, Protocol):
    """A planner with the "roadmap" capability: grown and expanded explicitly, then queried (OMPL's PRM)."""

    def milestoneCount(self) -> int: ...  # noqa: N802 (OMPL's names)

    def edgeCount(self) -> int: ...  # noqa: N802

    def growRoadmapPtc(self, ptc: ob.PlannerTerminationCondition) -> None: ...  # noqa: N802

    def expandRoadmapPtc(self, ptc: ob.PlannerTerminationCondition) -> None: ...  # noqa: N802


#: factory(si, params, edge_checker) -> planner; ``params`` are already checked against the spec.
PlannerFactory = Callable[[ob.SpaceInformation, dict[str, Any], EdgeChecker | None], ArmPlanner]
#: search(problem, params, seed, deadline, stats) -> (path of group configurations | None, proven-failure message |
#: None): a problem-aware planner's whole search; it raises a typed error to fail the request.
SearchFn = Callable[["PlanningProblem", dict[str, Any], int, float, "PlanStats"], tuple[np.ndarray | None, str | None]]


@dataclass(frozen=True)
class ArmPlannerSpec:
    """One registered arm planner (see module doc)."""

    id: str
    description: str
    factory: PlannerFactory | None  # an OMPL-style planner's; None for a problem-aware one
    params: Mapping[str, ParamSpec]
    capabilities: frozenset[str]
    search: SearchFn | None = None  # a problem-aware planner's; None: the factory's planner solved on OMPL's setup

    def has(self, capability: str) -> bool:
        return capability in self.capabilities


PLANNERS: dict[str, ArmPlannerSpec] = {}


def register(spec: ArmPlannerSpec) -> ArmPlannerSpec:
    """Add ``spec`` to :data:`PLANNERS` (replacing an entry of the same id)."""
    unknown = sorted(spec.capabilities - CAPABILITIES.keys())
    if unknown:
        known = ", ".join(CAPABILITIES)
        raise ValueError(f"planner {spec.id}: unknown capabilities {', '.join(unknown)}; known: {known}")
    for name, param in spec.params.items():
        if param.name != name:
            raise ValueError(f"planner {spec.id}: parameter {name!r} is declared as {param.name!r}")
    PLANNERS[spec.id] = spec
    return spec


def planner_ids() -> list[str]:
    """Registered ids, in registration order."""
    return list(PLANNERS)


def get_spec(planner_id: str) -> ArmPlannerSpec:
    """The spec of ``planner_id``; InvalidPlanner (naming the known ids) if it is not registered."""
    spec = PLANNERS.get(planner_id) if isinstance(planner_id, str) else None
    if spec is None:
        raise InvalidPlanner(f"unknown planner {planner_id!r:.60}; known: {', '.join(PLANNERS)}")
    return spec


def merged_params(planner_id: str, overrides: Mapping[str, Any] | None) -> dict[str, Any]:
    """Default parameters of ``planner_id`` updated with ``overrides``, each checked (unknown names raise)."""
    spec = get_spec(planner_id)
    try:
        return check_params(dict(spec.params), dict(overrides or {}), owner=f"planner {planner_id}")
    except InvalidRequest as exc:
        owner = f"planner {planner_id}"
        message = exc.message if exc.message.startswith(owner) else f"{owner}: {exc.message}"
        raise InvalidRequest(message, source="planner") from exc


def make_planner(
    planner_id: str, si: ob.SpaceInformation, params: Mapping[str, Any] | None = None, edge_checker=None
) -> ArmPlanner:
    """A configured planner instance of ``planner_id`` for ``si`` (``params`` override the defaults); InvalidPlanner
    for a problem-aware planner (it has no OMPL planner object)."""
    spec = get_spec(planner_id)
    if spec.factory is None:
        raise InvalidPlanner(f"planner {planner_id} is not an OMPL planner: it plans a PlanningProblem")
    return spec.factory(si, merged_params(planner_id, params), edge_checker)
