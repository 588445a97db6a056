"""A grid planner's cost options: Nav2's inflation costs, the travel-cost multiplier and the smoother.

:class:`CostSettings` holds the declared parameters (the registry turns them into planner parameters,
the CLI's ``--param`` and the node's parameters); :class:`CostModel` is what a planner keeps: the
settings checked against its robot's inscribed and circumscribed radii, the cost layer of a map
(``layer``), the per-cell weights of the search (``weights``) and the smoothing of a planned path.

The travel cost is Smac 2D's: a step of length ``l`` into a cell of cost ``c`` costs
``l * (1 + cost_travel_multiplier * c / 252)``, so a plan minimises its length plus the multiplier
times its cost integrated along it; 0 turns the cost layer off (the plain shortest path).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from maru_planner.base.budget import Deadline
from maru_planner.base.clearance import from_cell_units, to_cell_units
from maru_planner.base.costmap import NAV2_COST_SCALING_FACTOR, NAV2_INFLATION_RADIUS, CostLayer, cost_layer
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.smoother import SmootherParams, SmoothOutcome, Stretch, smooth_stretch
from maru_planner.errors import InvalidRequest
from maru_planner.params import ParamSpec, dataclass_params, param

# The distance field reaches this many cells past the inflation radius: the smoother's clearance guard
# (capped at the inflation radius) can then skip cells farther than that from every obstacle.
DISTANCE_MARGIN_CELLS = 3


@dataclass(frozen=True)
class CostSettings:
    """The cost and smoothing parameters every grid planner declares (Nav2's names where Nav2 has one)."""

    inflation_radius: float | None = param(
        None,
        "m: the cost decays to 0 here (Nav2); default Nav2's 0.55 or the circumscribed radius if larger",
        lower=0.0,
    )
    cost_scaling_factor: float = param(
        NAV2_COST_SCALING_FACTOR, "1/m: exponential decay rate of the cost (Nav2)", lower=0.0, upper=1e6
    )
    cost_travel_multiplier: float = param(
        0.0,
        "weight of the cost against length (Smac 2D: step length x (1 + this x cost / 252)); 0 = shortest",
        lower=0.0,
        upper=1e6,
    )
    smooth: bool = param(False, "smooth the path (Nav2 simple smoother; never nearer to obstacles, re-checked)")
    min_turning_radius: float = param(
        0.0, "m: the smoother turns no sharper than this (0 = in place allowed)", lower=0.0, upper=1e6
    )


COST_FIELDS = tuple(f.name for f in dataclasses.fields(CostSettings))


def cost_params(cost_travel_multiplier: float = 0.0) -> dict[str, ParamSpec]:
    """The cost parameters' specs, with this planner's default multiplier."""
    specs = dataclass_params(CostSettings)
    specs["inflation_radius"] = dataclasses.replace(specs["inflation_radius"], type=float)
    specs["cost_travel_multiplier"] = dataclasses.replace(
        specs["cost_travel_multiplier"], default=float(cost_travel_multiplier)
    )
    return specs


def split_cost_kwargs(kwargs: dict) -> tuple[dict, dict]:
    """(the cost settings' keyword arguments, the rest)."""
    costs = {k: v for k, v in kwargs.items() if k in COST_FIELDS}
    return costs, {k: v for k, v in kwargs.items() if k not in COST_FIELDS}


def _finite_non_negative(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not (math.isfinite(value) and value >= 0):
        raise InvalidRequest(f"parameter {name!r} must be a finite number >= 0, got {value}")
    return float(value)


class CostModel:
    """A planner's cost settings for a robot of the given inscribed / circumscribed radius (checked here)."""

    def __init__(self, settings: CostSettings, inscribed_radius: float, circumscribed_radius: float):
        self.settings = settings
        self.inscribed_radius = float(inscribed_radius)
        self.circumscribed_radius = float(circumscribed_radius)
        for name in ("cost_scaling_factor", "cost_travel_multiplier", "min_turning_radius"):
            _finite_non_negative(name, getattr(settings, name))
        if settings.inflation_radius is None:
            self.inflation_radius = max(NAV2_INFLATION_RADIUS, self.circumscribed_radius)
        else:
            self.inflation_radius = _finite_non_negative("inflation_radius", settings.inflation_radius)
        if self.inflation_radius < self.inscribed_radius:
            raise InvalidRequest(
                f"parameter 'inflation_radius' = {self.inflation_radius:g} m is smaller than the footprint's "
                f"inscribed radius {self.inscribed_radius:.3f} m"
            )
        if not isinstance(settings.smooth, bool):
            raise InvalidRequest(f"parameter 'smooth' must be true or false, got {settings.smooth!r}")

    @classmethod
    def of(cls, inscribed_radius: float, circumscribed_radius: float, **settings) -> CostModel:
        return cls(CostSettings(**settings), inscribed_radius, circumscribed_radius)

    @property
    def multiplier(self) -> float:
        return float(self.settings.cost_travel_multiplier)

    @property
    def cost_aware(self) -> bool:
        return self.multiplier > 0

    @property
    def needs_layer(self) -> bool:
        return self.cost_aware or self.settings.smooth

    def layer(self, grid: OccupancyGrid, deadline: Deadline | None = None, reach: float = 0.0) -> CostLayer:
        """The cost layer of ``grid``; its distances reach at least ``reach`` m (a grown map's radius)."""
        margin = max(reach - self.inflation_radius, 0.0) + DISTANCE_MARGIN_CELLS * grid.resolution
        return cost_layer(
            grid,
            self.inscribed_radius,
            self.circumscribed_radius,
            self.inflation_radius,
            self.settings.cost_scaling_factor,
            deadline,
            margin,
        )

    def weights(self, layer: CostLayer | None) -> np.ndarray | None:
        """Per-cell step-length factor minus one for the search, or None when the plan is the plain shortest."""
        if layer is None or not self.cost_aware:
            return None
        return layer.traversal_weights(self.multiplier)

    def smoother_params(self) -> SmootherParams:
        return SmootherParams(min_turning_radius=float(self.settings.min_turning_radius))

    def smooth(
        self,
        grid: OccupancyGrid,
        xy: np.ndarray,
        layer: CostLayer,
        stretches: list[Stretch],
        deadline: Deadline | None = None,
    ) -> tuple[np.ndarray, dict]:
        """Map-frame ``xy`` (n, 2) with each stretch smoothed (see ``smoother.py``) and a summary for the stats.

        ``grid`` gives the geometry (a grown map will do); distances are to ``layer.obstacles``, the map's own.
        """
        xy = np.array(xy, dtype=float)
        points = to_cell_units(grid, xy)
        dist_cells = layer.distance / grid.resolution
        cap = self.inflation_radius / grid.resolution
        info = {"stretches": len(stretches), "sweeps": 0, "moved": 0, "accepted": True}
        params = self.smoother_params()
        for stretch in stretches:
            out: SmoothOutcome = smooth_stretch(
                points, stretch, layer.obstacles, dist_cells, cap, params, grid.resolution, deadline
            )
            info["sweeps"] = max(info["sweeps"], out.sweeps)
            if deadline is not None and deadline.cancelled:
                deadline.raise_timeout("smoothing the path")  # PlanningCancelled: the caller wants no answer
            if not out.accepted:
                info["accepted"] = False
                continue
            inner = slice(stretch.first + 1, stretch.last)  # the ends stay exactly where they were
            points[stretch.first : stretch.last + 1] = out.points
            xy[inner] = from_cell_units(grid, points[inner])
            info["moved"] += out.moved
        return xy, info
