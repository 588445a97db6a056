"""The planning problem every planner and stage is given, never the facade: one request checked and resolved
(:func:`~maru_planner.planning.adapters.build_problem`), with the context it is planned in."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from maru_planner.monitor import PlanMonitor
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.constraints import PathConstraints
from maru_planner.planning.context import PlanningContext
from maru_planner.planning.space import EdgeChecker, GroupSetup, full_configurations
from maru_planner.planning.types import MotionRequest, MotionResult


@dataclass
class PlanningProblem:
    """One request, checked and resolved: what to plan, for which robot, on which checker, by when."""

    request: MotionRequest
    context: PlanningContext
    planner_id: str  # a registered planner (planning/planners/registry.py)
    monitor: PlanMonitor
    t0: float
    budget: float
    seed: int
    resolution: float
    indices: list[int]
    joint_names: list[str]
    start_full: np.ndarray
    goal_full: np.ndarray
    constraints: PathConstraints
    checker: Any  # the search's (the context's, padded by the margin when the path is certified with one)
    setup: GroupSetup  # the group's OMPL setup and edge check on ``checker``
    rng: np.random.Generator  # seeded by ``seed``: the planner's and the simplification's random stream
    margin: float  # m: the clearance the certified path keeps (the request's safety_margin, else the configuration's)
    # re-plan this request at a motion resolution (the path stages only; set by the pipeline)
    replan: Callable[[float], MotionResult] | None = None
    margin_kept: float = 0.0  # m: the clearance the certified path keeps (set by certification)

    @property
    def robot(self) -> Any:
        return self.context.robot

    @property
    def config(self) -> PlannerConfig:
        return self.context.config

    @property
    def deadline(self) -> float:
        return self.t0 + self.budget

    @property
    def start(self) -> np.ndarray:
        return self.start_full[self.indices]

    @property
    def goal(self) -> np.ndarray:
        return self.goal_full[self.indices]

    @property
    def constrained(self) -> bool:
        return not self.constraints.empty

    @property
    def edges(self) -> EdgeChecker:
        return self.setup.edges

    def full(self, group_states: np.ndarray) -> np.ndarray:
        """Group configurations (rows) as full ones, the joints outside the group at their start values."""
        return full_configurations(self.start_full, self.indices, np.atleast_2d(np.asarray(group_states, dtype=float)))
