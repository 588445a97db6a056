"""A toy base planner registered from outside the package: a point robot driving the straight segment.

Importing this module is the whole of "adding a planner": one ``registry.register`` call. Run as
``python -m toy_base_planner node|cli ...`` (with ``test/`` on PYTHONPATH) it starts base_planner_node
or maru-base-plan with the toy registered; ``pytest -p toy_base_planner`` loads it into a test run.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from maru_planner.base import registry
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.planner import DiscPlanner, Endpoint, PlanRun
from maru_planner.errors import NoPath
from maru_planner.params import ParamSpec

TOY_ID = "toy_straight"


class StraightLinePlanner(DiscPlanner):
    """The straight segment start -> goal for a point robot, sampled ``samples_per_cell`` times per cell."""

    def __init__(self, footprint=None, samples_per_cell: int = 2):
        super().__init__(0.0)
        self.samples_per_cell = samples_per_cell

    def search(self, space: OccupancyGrid, start: Endpoint, goal: Endpoint, run: PlanRun) -> np.ndarray:
        length = math.dist(start.pose[:2], goal.pose[:2])
        n = max(2, int(math.ceil(length / space.resolution * self.samples_per_cell)) + 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        path = np.asarray(start.pose) + t * (np.asarray(goal.pose) - np.asarray(start.pose))
        for x, y, _ in path:
            run.deadline.check("toy")
            run.stats.collision_checks += 1
            if space.occupied[space.world_to_cell(x, y)]:
                raise NoPath(f"no path: the straight segment hits an obstacle at ({x:.2f}, {y:.2f})")
        run.stats.expansions = n
        run.message = "straight segment is free"
        return path


registry.register(
    registry.BasePlannerSpec(
        TOY_ID,
        "toy: a point robot on the straight segment",
        StraightLinePlanner,
        {"samples_per_cell": ParamSpec("samples_per_cell", 2, "samples per cell along the segment", lower=1, upper=10)},
    )
)


def main(argv: list[str]) -> int:
    # imported here so that the CLI does not load rclpy, nor the node the CLI
    if argv[:1] == ["node"]:
        from maru_planner.ros.base_planner_node import main as node_main

        return node_main()
    from maru_planner.base.cli import main as cli_main

    return cli_main(argv[1:])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
