"""The tunnel planner (paper 003, ``tunnel.py``) as a base planner on an ``OccupancyGrid`` (registry id ``tunnel``).

The paper's planner runs on the grid grown by the robot's radius. The cost layer is an option
(``cost_travel_multiplier`` > 0; off by default, the paper's behaviour): the line-of-sight shortcuts
then never cross a cell costlier than the chain of cells they replace. ``smooth`` smooths the
waypoint path on the grown map (``smoother.py``).
"""

from __future__ import annotations

import numpy as np

from maru_planner.base.cost_model import CostSettings, split_cost_kwargs
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.planner import DiscPlanner, Endpoint, PlanRun
from maru_planner.base.result import PlanStats
from maru_planner.base.tunnel import TunnelPlanner, TunnelStats


def segment_headings(xy: np.ndarray, start_theta: float, goal_theta: float) -> np.ndarray:
    """θ of each pose along its outgoing segment; the ends keep the request's θ."""
    theta = np.empty(len(xy))
    if len(xy) > 1:
        d = np.diff(xy, axis=0)
        theta[:-1] = np.arctan2(d[:, 1], d[:, 0])
    if len(xy):
        theta[0] = start_theta
        theta[-1] = goal_theta
    return theta


def cells_to_path(grid, cells: np.ndarray, start_theta: float, goal_theta: float) -> np.ndarray:
    """(row, col) cells → (x, y, θ) rows; θ follows each segment, the ends keep the request's θ."""
    if len(cells) == 0:
        return np.zeros((0, 3))
    xy = grid.cells_to_world(cells)
    return np.column_stack([xy, segment_headings(xy, start_theta, goal_theta)])


class TunnelGridPlanner(DiscPlanner):
    """Registry entry ``tunnel``: the tunnel planner on an ``OccupancyGrid`` for a disc robot.

    Obstacles are grown by ``robot_radius`` metres (default: the footprint's
    circumradius, 0.25 m without a footprint — the paper's robot). Other
    keyword arguments are :class:`~maru_planner.base.tunnel.TunnelParams` fields and
    :class:`~maru_planner.base.cost_model.CostSettings` fields.
    """

    default_radius = 0.25

    def __init__(self, footprint=None, robot_radius: float | None = None, **params):
        costs, tunnel_params = split_cost_kwargs(params)
        super().__init__(robot_radius, footprint, CostSettings(**costs))
        self.planner = TunnelPlanner(**tunnel_params)

    @property
    def robot_radius(self) -> float:
        return self.radius

    def new_stats(self) -> PlanStats:
        return TunnelStats(deciding_stage="tunnel")

    def search(self, space: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        layer = run.layers.get("costmap")
        cost = layer.cost if layer is not None and self.costs.cost_aware else None
        plan = self.planner.plan_cells(
            space.occupied, start.cell, goal.cell, run.deadline, run.stats_as(TunnelStats), cost=cost
        )
        run.stats.collision_checks = run.stats.expansions
        last = plan.attempts[-1] if plan.attempts else None
        run.stats.deciding_stage = f"tunnel b={last.big_cell_size}" if last else "tunnel"
        run.layers.update(attempts=plan.attempts, raw_cells=plan.raw_cells, waypoints=plan.waypoints)
        if plan.error is not None:
            raise plan.error
        path = cells_to_path(space, plan.waypoints, start.pose[2], goal.pose[2])
        path[0, :2] = start.pose[:2]
        path[-1, :2] = goal.pose[:2]
        run.stats.cost = float(np.sum(np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1)))
        run.message = plan.message
        return self.smooth_path(space, path, run, lambda xy: segment_headings(xy, start.pose[2], goal.pose[2]))
