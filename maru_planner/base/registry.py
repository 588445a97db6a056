"""Base planners by id: one :class:`BasePlannerSpec` each (factory, declared parameters, capabilities).

Adding a planner is its file plus one ``register(BasePlannerSpec(...))``: ``maru-base-plan``
(``--planner``, ``--help``), ``base_planner_node`` and the parametrised tests read this table.

Capabilities say what a caller must hand the factory:

- ``uses_footprint``: the factory gets the robot footprint (else None);
- ``needs_headings``: the node passes its ``headings`` parameter (a declared ``headings`` param);
- ``world_3d``: may plan on a 3-D world (``world`` param; the CLI's ``--world``, the node's ``biped_world``);
- ``proves_no_path``: may answer ``no_path_proven`` without a search.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from maru_planner.base.astar import DEFAULT_COST_TRAVEL_MULTIPLIER, GridAStarPlanner, astar_2d
from maru_planner.base.biped.planners import biped_track, biped_wall
from maru_planner.base.biped.track import TrackParams
from maru_planner.base.biped.wall import WallParams
from maru_planner.base.budget import DEFAULT_TIME_LIMIT
from maru_planner.base.clearance import path_clearance
from maru_planner.base.cost_model import cost_params
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.mspp import LocalMultiStagePlanner, MultiStagePlanner
from maru_planner.base.planner import BasePlanner
from maru_planner.base.result import BasePlanResult
from maru_planner.base.se2 import SE2AStarPlanner
from maru_planner.base.tunnel import TunnelGridPlanner, TunnelParams
from maru_planner.errors import InvalidPlanner
from maru_planner.params import ParamSpec, check_params, dataclass_params

USES_FOOTPRINT = "uses_footprint"
NEEDS_HEADINGS = "needs_headings"
WORLD_3D = "world_3d"
PROVES_NO_PATH = "proves_no_path"
CAPABILITIES = frozenset({USES_FOOTPRINT, NEEDS_HEADINGS, WORLD_3D, PROVES_NO_PATH})

PlannerFactory = Callable[..., BasePlanner]


@dataclass(frozen=True)
class BasePlannerSpec:
    """One base planner: ``factory(footprint, **params)`` builds it; ``params`` are all it accepts."""

    id: str
    description: str
    factory: PlannerFactory
    params: dict[str, ParamSpec] = field(default_factory=dict)
    capabilities: frozenset[str] = frozenset()

    def __post_init__(self) -> None:
        unknown = set(self.capabilities) - CAPABILITIES
        if unknown:
            raise ValueError(f"base planner {self.id!r}: unknown capabilities {sorted(unknown)}")
        if (NEEDS_HEADINGS in self.capabilities) != ("headings" in self.params):
            raise ValueError(f"base planner {self.id!r}: needs_headings goes with a 'headings' parameter")
        if (WORLD_3D in self.capabilities) != ("world" in self.params):
            raise ValueError(f"base planner {self.id!r}: world_3d goes with a 'world' parameter")

    def has(self, capability: str) -> bool:
        return capability in self.capabilities


SPECS: dict[str, BasePlannerSpec] = {}
DEFAULT_PLANNER = "mspp"


def register(spec: BasePlannerSpec) -> BasePlannerSpec:
    """Add ``spec`` (its id must be new); returns it."""
    if spec.id in SPECS:
        raise ValueError(f"base planner {spec.id!r} is already registered")
    SPECS[spec.id] = spec
    return spec


def planner_ids() -> list[str]:
    return sorted(SPECS)


def spec(planner_id: str) -> BasePlannerSpec:
    """The spec of ``planner_id`` (empty = DEFAULT_PLANNER); InvalidPlanner naming the known ids."""
    found = SPECS.get(planner_id or DEFAULT_PLANNER)
    if found is None:
        raise InvalidPlanner(f"unknown base planner {str(planner_id)[:40]!r}; known: {', '.join(planner_ids())}")
    return found


def make_planner(planner_id: str, footprint: Sequence | np.ndarray | None, **params: Any) -> BasePlanner:
    """Build a planner; InvalidPlanner for an unknown id, InvalidRequest for a bad parameter or footprint."""
    entry = spec(planner_id)
    values = check_params(entry.params, params, f"base planner {entry.id!r}")
    return entry.factory(footprint if entry.has(USES_FOOTPRINT) else None, **values)


def warm_up() -> None:
    """Load every planner's compiled kernels once (a long-running caller's first request then pays no JIT load)."""
    grid = OccupancyGrid(np.pad(np.zeros((8, 8), bool), 1, constant_values=True), 0.1)
    footprint = np.array([[0.1, 0.05], [-0.1, 0.05], [-0.1, -0.05], [0.1, -0.05]])
    for planner_id in planner_ids():
        plan(planner_id, grid, (0.25, 0.25, 0.0), (0.75, 0.75, 1.0), footprint)
    for planner_id in ("astar", "se2"):  # the smoother and the plain (JPS) search
        plan(planner_id, grid, (0.25, 0.25, 0.0), (0.75, 0.75, 0.0), footprint, smooth=True)
        plan(planner_id, grid, (0.25, 0.25, 0.0), (0.75, 0.75, 0.0), footprint, cost_travel_multiplier=0.0)
    # the weighted A* kernel: MSPP's guide path past narrow passages, which this open grid never needs
    astar_2d(grid.occupied, (1, 1), (8, 8), cell_cost=np.ones(grid.occupied.shape))
    path_clearance(grid, np.array([[0.25, 0.25], [0.75, 0.75]]))


def plan(
    planner_id: str,
    grid: OccupancyGrid | None,
    start: Sequence[float],
    goal: Sequence[float],
    footprint: Sequence | np.ndarray | None,
    *,
    time_limit: float = DEFAULT_TIME_LIMIT,
    **params: Any,
) -> BasePlanResult:
    """Plan with the named planner within ``time_limit`` seconds."""
    return make_planner(planner_id, footprint, **params).plan(grid, start, goal, time_limit=time_limit)


# ------------------------------------------------------------------------- the planners
HEADINGS = ParamSpec("headings", 32, "SE(2) heading discretisation (the paper: 31)", lower=1, upper=3600)
ROTATION_WEIGHT = ParamSpec(
    "rotation_weight",
    None,
    "metres per radian of turning in place; default R_max",
    lower=0.0,
    optional=True,
    type=float,
)
WORLD = ParamSpec(
    "world",
    None,
    "3-D world YAML (relative paths also under config/); none = plan on the grid",
    optional=True,
    type=str,
)


def _params(*specs: ParamSpec) -> dict[str, ParamSpec]:
    return {s.name: s for s in specs}


def _robot_radius(default: str) -> ParamSpec:
    return ParamSpec(
        "robot_radius",
        None,
        f"disc radius (m): the obstacle growth; default {default}",
        lower=0.0,
        optional=True,
        type=float,
    )


COST_AWARE = cost_params(DEFAULT_COST_TRAVEL_MULTIPLIER).values()  # astar, se2: Nav2's cost-aware planning
PAPER_COSTS = cost_params(0.0).values()  # the papers' planners: the cost layer as an option

register(
    BasePlannerSpec(
        "astar",
        "2-D A* on the map grown by robot_radius (the footprint's circumradius), Nav2's inflation costs "
        "(cost_travel_multiplier=0: the shortest path, JPS)",
        GridAStarPlanner,
        _params(_robot_radius("the footprint's circumradius"), *COST_AWARE),
        frozenset({USES_FOOTPRINT}),
    )
)
register(
    BasePlannerSpec(
        "se2",
        "complete SE(2) A* for the footprint polygon over all headings (paper 002's full search), cost-aware",
        SE2AStarPlanner,
        _params(HEADINGS, ROTATION_WEIGHT, *COST_AWARE),
        frozenset({USES_FOOTPRINT, NEEDS_HEADINGS}),
    )
)
register(
    BasePlannerSpec(
        "mspp",
        "paper 002's multi-stage planner: ECA (proves no path) -> BAA (2-D A*) -> full SE(2) A*",
        MultiStagePlanner,
        _params(HEADINGS, ROTATION_WEIGHT, *PAPER_COSTS),
        frozenset({USES_FOOTPRINT, NEEDS_HEADINGS, PROVES_NO_PATH}),
    )
)
register(
    BasePlannerSpec(
        "mspp_local",
        "MSPP with the SE(2) search only in windows around the guide path's narrow parts",
        LocalMultiStagePlanner,
        _params(
            HEADINGS,
            ROTATION_WEIGHT,
            ParamSpec(
                "local_margin",
                None,
                "window margin around a narrow run (m); default 2 R_max",
                lower=0.0,
                optional=True,
                type=float,
            ),
            ParamSpec(
                "narrow_penalty", 4.0, "guide-path cost per cell within R_max of an obstacle", lower=0.0, upper=1e6
            ),
            *PAPER_COSTS,
        ),
        frozenset({USES_FOOTPRINT, NEEDS_HEADINGS, PROVES_NO_PATH}),
    )
)
register(
    BasePlannerSpec(
        "tunnel",
        "paper 003's heuristic tunnel planner (TFP -> LCRP -> PFP) for a disc robot",
        TunnelGridPlanner,
        _params(
            _robot_radius("the footprint's circumradius, 0.25 without"),
            *dataclass_params(TunnelParams).values(),
            *PAPER_COSTS,
        ),
        frozenset({USES_FOOTPRINT}),
    )
)
register(
    BasePlannerSpec(
        "biped_track",
        "paper 004's track following (Voronoi mid-lines, turning rule) for a biped",
        biped_track,
        _params(WORLD, *dataclass_params(TrackParams).values()),
        frozenset({USES_FOOTPRINT, WORLD_3D}),
    )
)
register(
    BasePlannerSpec(
        "biped_wall",
        "paper 004's virtual-wall walk (free rotation ranges) for a biped",
        biped_wall,
        _params(WORLD, *dataclass_params(WallParams).values()),
        frozenset({USES_FOOTPRINT, WORLD_3D}),
    )
)
