"""A toy arm planner registered like any other: the straight line if it is free, else a tiny RRT.

Loaded as a pytest plugin (``-p planning_toy_planner``) it registers itself before collection, so
the parametrised planner tests pick it up; ``test_arm_planner_registry`` registers it in-process
with :data:`TOY_SPEC`. Nothing outside this file names it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from maru_planner.params import ParamSpec
from maru_planner.planning.planners.planner_params import PlannerParams
from maru_planner.planning.planners.registry import ArmPlannerSpec, register

TOY_PARAMS = {
    "step": ParamSpec("step", 0.05, "RRT extension length (rad)", lower=1e-3, upper=1.0),
    "goal_bias": ParamSpec("goal_bias", 0.2, "probability of steering toward the goal", lower=0.0, upper=1.0),
}


class StraightLineOrRRT(ob.Planner):
    """Straight line start→goal when it is free, else a brute-force-nearest-neighbour RRT."""

    def __init__(self, si: ob.SpaceInformation):
        super().__init__(si, "Toy")
        self._si = si
        self._values = {name: spec.default for name, spec in TOY_PARAMS.items()}
        self._params = PlannerParams("Toy")
        for name, spec in TOY_PARAMS.items():
            self._params.declare_param(spec, lambda v, n=name: self._values.__setitem__(n, v),
                                       lambda n=name: self._values[n])  # fmt: skip
        self._seed = ou.RNG().uniformInt(0, 2**31 - 2)  # drawn from OMPL's seeded generator
        self.nodes = np.zeros((0, si.getStateDimension()))

    def params(self) -> PlannerParams:
        return self._params

    def graph_size(self) -> tuple[int, int]:
        return len(self.nodes), max(0, len(self.nodes) - 1)

    def solve(self, ptc: ob.PlannerTerminationCondition) -> ob.PlannerStatus:
        space = self._si.getStateSpace()
        dim = space.getDimension()
        lower = np.array([space.getBounds().low[i] for i in range(dim)])
        upper = np.array([space.getBounds().high[i] for i in range(dim)])
        inputs = self.getPlannerInputStates()
        start_state, goal_state = inputs.nextStart(), inputs.nextGoal()
        start = np.array([start_state[i] for i in range(dim)])
        goal = np.array([goal_state[i] for i in range(dim)])
        rng = np.random.default_rng(self._seed)
        self.nodes, parents = start[None], [-1]
        while not ptc():
            near = int(np.argmin(np.linalg.norm(self.nodes - goal, axis=1)))
            if self._free(self.nodes[near], goal):
                return self._finish(parents, near, goal)
            target = goal if rng.random() < self._values["goal_bias"] else rng.uniform(lower, upper)
            near = int(np.argmin(np.linalg.norm(self.nodes - target, axis=1)))
            direction = target - self.nodes[near]
            new = self.nodes[near] + direction * min(1.0, self._values["step"] / max(np.linalg.norm(direction), 1e-12))
            if self._free(self.nodes[near], new):
                self.nodes = np.vstack([self.nodes, new])
                parents.append(near)
        return ob.PlannerStatus(ob.PlannerStatus.TIMEOUT)

    def _free(self, a: np.ndarray, b: np.ndarray) -> bool:
        return bool(self._si.checkMotion(self._state(a), self._state(b)))

    def _state(self, q: np.ndarray) -> Any:
        state = self._si.allocState()
        for i, v in enumerate(q):
            state[i] = float(v)
        return state

    def _finish(self, parents: list[int], last: int, goal: np.ndarray) -> ob.PlannerStatus:
        chain = [last]
        while parents[chain[-1]] >= 0:
            chain.append(parents[chain[-1]])
        path = og.PathGeometric(self._si)
        for q in [*self.nodes[chain[::-1]], goal]:
            path.append(self._state(q))
        self.getProblemDefinition().addSolutionPath(path, False, 0.0, self.getName())
        return ob.PlannerStatus(ob.PlannerStatus.EXACT_SOLUTION)


def _toy(si: ob.SpaceInformation, params: dict[str, Any], _edge_checker: object) -> StraightLineOrRRT:
    planner = StraightLineOrRRT(si)
    planner.params().set_params(params)
    return planner


TOY_SPEC = ArmPlannerSpec(
    "Toy", "straight line if free, else a tiny RRT (test planner)", _toy, TOY_PARAMS, frozenset({"tree"})
)


def pytest_configure(config: object) -> None:
    """Plugin entry: register the toy before the test modules are collected."""
    register(TOY_SPEC)
