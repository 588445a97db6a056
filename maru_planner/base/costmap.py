"""Nav2's inflation layer on an :class:`OccupancyGrid`: a cost per cell from the exact distance to obstacles.

Semantics and names follow Nav2's ``nav2_costmap_2d`` (``inflation_layer.cpp``, ``cost_values.hpp``):

- an occupied cell is ``LETHAL_OBSTACLE`` (254);
- a cell whose centre lies within the footprint's ``inscribed_radius`` of an occupied cell's centre is
  ``INSCRIBED_INFLATED_OBSTACLE`` (253): the robot's centre there means a collision at every heading;
- farther out, to ``inflation_radius``, the cost decays as Nav2 computes it:
  ``int((253 - 1) * exp(-cost_scaling_factor * (d - inscribed_radius)))``;
- beyond ``inflation_radius`` the cost is ``FREE_SPACE`` (0).

Distances are between cell centres (the grid's inflation convention), from scipy's exact Euclidean
distance transform, computed in strips of rows that each see the obstacles within ``inflation_radius``
(farther ones cannot reach), so the request's deadline is checked between strips and a 4096 x 4096 map
holds its distances (float64, 128 MB) and costs (uint8). Comparisons with the radii allow 1e-9 cell, as
``OccupancyGrid.inflate`` does, so the lethal cells of a disc robot are exactly its grown map.

:func:`to_occupancy_values` scales costs to ``nav_msgs/OccupancyGrid`` values as Nav2's costmap publisher
does (0 free, 1..98 inflated, 99 inscribed, 100 lethal, -1 unknown).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maru_planner.base.budget import Deadline
from maru_planner.base.grid import OccupancyGrid
from maru_planner.errors import InvalidRequest

FREE_SPACE = 0
MAX_NON_OBSTACLE = 252
INSCRIBED_INFLATED_OBSTACLE = 253
LETHAL_OBSTACLE = 254
NO_INFORMATION = 255

NAV2_INFLATION_RADIUS = 0.55  # m, Nav2's default
NAV2_COST_SCALING_FACTOR = 10.0  # 1/m, Nav2's default


def check_inflation(inflation_radius: float, cost_scaling_factor: float, inscribed_radius: float) -> None:
    """InvalidRequest (one line, naming the parameter) for values Nav2's layer cannot use."""
    for name, value in (("inflation_radius", inflation_radius), ("cost_scaling_factor", cost_scaling_factor)):
        if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
            raise InvalidRequest(f"parameter {name!r} must be a finite number >= 0, got {value}")
    if inflation_radius < inscribed_radius:
        raise InvalidRequest(
            f"parameter 'inflation_radius' = {inflation_radius:g} m is smaller than the footprint's inscribed "
            f"radius {inscribed_radius:.3f} m: cells the robot cannot reach would look free"
        )


def cost_of_distance(
    distance: np.ndarray,
    inscribed_radius: float,
    inflation_radius: float,
    cost_scaling_factor: float,
    guard: float = 0.0,
) -> np.ndarray:
    """Nav2's cost (uint8) of cells at ``distance`` metres (centre to centre) from the nearest obstacle.

    ``guard`` (metres) is added to both radii in the comparisons (rounding of ``cells * resolution``).
    """
    d = np.asarray(distance, dtype=np.float64)
    cost = np.full(d.shape, FREE_SPACE, dtype=np.uint8)
    band = d <= inflation_radius + guard
    near = d[band]
    with np.errstate(over="ignore"):
        factor = np.exp(-cost_scaling_factor * np.maximum(near - inscribed_radius, 0.0))
    values = ((INSCRIBED_INFLATED_OBSTACLE - 1) * factor).astype(np.uint8)  # truncation, as Nav2's cast
    values[near <= inscribed_radius + guard] = INSCRIBED_INFLATED_OBSTACLE
    values[near == 0.0] = LETHAL_OBSTACLE
    cost[band] = values
    return cost


@dataclass
class CostLayer:
    """A map's Nav2 costs (uint8, the grid's shape) and the numbers that made them.

    ``obstacles`` are the occupied cells it was made from; ``distance`` holds the exact centre-to-centre
    distance to the nearest obstacle (metres, float64) where it is at most ``inflation_radius`` (plus the
    margin :func:`cost_layer` was given), ``inf`` elsewhere.
    """

    cost: np.ndarray
    distance: np.ndarray
    obstacles: np.ndarray  # the occupied cells it was made from (the map's, not a grown one)
    resolution: float
    inscribed_radius: float
    circumscribed_radius: float
    inflation_radius: float
    cost_scaling_factor: float

    def lethal(self) -> np.ndarray:
        """Cells the robot's centre may not enter at any heading (cost >= INSCRIBED_INFLATED_OBSTACLE)."""
        return self.cost >= INSCRIBED_INFLATED_OBSTACLE

    def traversal_weights(self, cost_travel_multiplier: float) -> np.ndarray:
        """Per-cell extra factor of a step's length: ``multiplier * cost / 252`` (Smac 2D's normalised cost)."""
        scale = float(cost_travel_multiplier) / MAX_NON_OBSTACLE
        return np.minimum(self.cost, MAX_NON_OBSTACLE).astype(np.float64) * scale


def cost_layer(
    grid: OccupancyGrid,
    inscribed_radius: float,
    circumscribed_radius: float,
    inflation_radius: float,
    cost_scaling_factor: float,
    deadline: Deadline | None = None,
    distance_margin: float = 0.0,
) -> CostLayer:
    """The inflation layer of ``grid`` (its ``occupied`` cells are the obstacles); checks the parameters first.

    ``distance_margin`` (m): the layer's ``distance`` stays exact that far past ``inflation_radius``.
    """
    check_inflation(inflation_radius, cost_scaling_factor, inscribed_radius)
    distance = grid.distance_field(inflation_radius + max(distance_margin, 0.0), deadline)
    guard = 1e-9 * grid.resolution
    cost = cost_of_distance(distance, inscribed_radius, inflation_radius, cost_scaling_factor, guard)
    return CostLayer(
        cost,
        distance,
        grid.occupied,
        grid.resolution,
        float(inscribed_radius),
        float(circumscribed_radius),
        float(inflation_radius),
        float(cost_scaling_factor),
    )


def _translation_table() -> np.ndarray:
    """Nav2's costmap_2d_publisher table: cost 0..255 -> OccupancyGrid value."""
    table = np.empty(256, dtype=np.int8)
    table[0] = 0
    table[1:253] = 1 + (97 * (np.arange(1, 253) - 1)) // 251
    table[INSCRIBED_INFLATED_OBSTACLE] = 99
    table[LETHAL_OBSTACLE] = 100
    table[NO_INFORMATION] = -1
    return table


COST_TRANSLATION_TABLE = _translation_table()


def to_occupancy_values(cost: np.ndarray, unknown: np.ndarray | None = None) -> np.ndarray:
    """Costs as ``nav_msgs/OccupancyGrid`` values (int8, Nav2's scaling); ``unknown`` cells become -1."""
    values = COST_TRANSLATION_TABLE[np.asarray(cost, dtype=np.uint8)]
    if unknown is not None:
        values = np.where(unknown, np.int8(-1), values)
    return values
