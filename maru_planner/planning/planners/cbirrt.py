"""CBiRRT, planning with path constraints (Berenson, Srinivasa, Ferguson, Kuffner 2009).

RRT-Connect in the group's joint space where every extension step is *projected* onto the constraint
region (:meth:`PathConstraints.project`: damped least squares on the violated components), so both
trees only hold states that satisfy the constraints. An edge between consecutive states (at most
``step`` rad long) is kept only if its states every ``config.resolution`` rad are collision-free and
satisfy the constraints too (constrained edge interpolation), so the path -- and the trajectory, which
stays within :data:`~maru_planner.planning.cartesian.BLEND_DEVIATION` rad of it -- holds the constraint
all along. The pipeline for a request with path constraints then shortcuts the path (checked the same way,
:func:`constrained_edge_valid`), certifies it (no repair: a repair would not know the constraints) and times it
densely (``planning/stages``).

This is the equivalent of OMPL's projection-based constrained planning (``ProjectedStateSpace``), whose
Python bindings OMPL 2.0.1 does not expose in a usable form (no ``Constraint`` subclassing). A problem-aware
planner: registered with the ``path_constraints`` capability, given the :class:`PlanningProblem`, cancelled
through its monitor.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from maru_planner import errors
from maru_planner.params import ParamSpec
from maru_planner.planning.planners.registry import ArmPlannerSpec, register
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.space import edge_states

PLANNER_ID = "CBiRRT"
STEP = ParamSpec("step", 0.1, "largest joint move (rad) of one projected extension step", lower=1e-3, upper=1.0)
INSET = ParamSpec("inset", 0.2, "share of each tolerance projection keeps free inside the bound", lower=0.0, upper=0.9)
PARAMS = {STEP.name: STEP, INSET.name: INSET}
DESCRIPTION = "constrained bidirectional RRT: RRT-Connect with every step projected onto the path constraints"
CONNECT_DISTANCE = 1e-3  # rad: the trees meet when a state comes this close to the other tree's
SEARCH_SHARE = 0.8  # of the budget: the search ends by then, leaving the rest to shortcutting, proof and timing


def constrained_edge_valid(problem: PlanningProblem) -> Callable[[np.ndarray, np.ndarray], bool]:
    """``edge_valid(qa, qb)``: every state of qa -> qb at the motion resolution is free and keeps the constraints."""
    robot, constraints, checker = problem.robot, problem.constraints, problem.checker
    resolution = problem.config.resolution

    def edge_valid(qa: np.ndarray, qb: np.ndarray) -> bool:
        full = problem.full(edge_states(qa, qb, resolution))
        if not all(constraints.satisfied(robot, q) for q in full):
            return False
        return int(checker.first_invalid(full)) < 0

    return edge_valid


def search(problem: PlanningProblem, params: dict[str, Any], _seed: int, deadline: float,
           stats: Any) -> tuple[np.ndarray | None, str | None]:  # fmt: skip
    """The constrained search (module doc) on ``problem.rng``, until ``deadline`` or its share of the budget."""
    step, inset = float(params["step"]), float(params["inset"])
    indices = np.asarray(problem.indices)
    robot, constraints = problem.robot, problem.constraints

    def project(q: np.ndarray) -> np.ndarray | None:
        projected = constraints.project(robot, problem.full(q)[0], indices, inset)
        return None if projected is None else projected[indices]

    extend = _Extender(project, constrained_edge_valid(problem), step)
    end = min(deadline, problem.t0 + SEARCH_SHARE * problem.budget)
    return _cbirrt(problem, extend, end, stats), None


class _Extender:
    """Constrained extension: steps of at most ``step`` rad, each projected, each edge checked."""

    def __init__(self, project: Callable[[np.ndarray], np.ndarray | None],
                 edge_valid: Callable[[np.ndarray, np.ndarray], bool], step: float):  # fmt: skip
        self.project, self.edge_valid, self.step = project, edge_valid, step

    def __call__(self, tree: _Tree, target: np.ndarray) -> tuple[int, bool]:
        """From the nearest node towards ``target``: (last node added or reached, reached)."""
        index = tree.nearest(target)
        q = tree.nodes[index]
        while True:
            gap = target - q
            distance = float(np.abs(gap).max())
            if distance < CONNECT_DISTANCE:
                return index, True
            step = target if distance <= self.step else q + gap * (self.step / distance)
            projected = self.project(step)
            if projected is None:
                return index, False
            moved = float(np.abs(projected - q).max())
            if moved < 1e-6 or moved > 2 * self.step or np.abs(target - projected).max() >= distance:
                return index, False
            if not self.edge_valid(q, projected):
                return index, False
            index, q = tree.add(projected, index), projected


class _Tree:
    def __init__(self, root: np.ndarray, capacity: int = 1024):
        self.nodes = np.empty((capacity, len(root)))
        self.nodes[0] = root
        self.parent = [-1]

    def __len__(self) -> int:
        return len(self.parent)

    def add(self, q: np.ndarray, parent: int) -> int:
        if len(self) == len(self.nodes):
            self.nodes = np.vstack([self.nodes, np.empty_like(self.nodes)])
        self.nodes[len(self)] = q
        self.parent.append(parent)
        return len(self) - 1

    def nearest(self, q: np.ndarray) -> int:
        return int(np.argmin(np.abs(self.nodes[: len(self)] - q).max(axis=1)))

    def branch(self, index: int) -> list[np.ndarray]:
        """The states from the root to ``index``."""
        out = []
        while index >= 0:
            out.append(self.nodes[index])
            index = self.parent[index]
        return out[::-1]


def _cbirrt(problem: PlanningProblem, extend: _Extender, deadline: float, stats: Any) -> np.ndarray:
    lower = problem.robot.lower_limits[problem.indices]
    upper = problem.robot.upper_limits[problem.indices]
    trees = (_Tree(problem.start), _Tree(problem.goal))
    grow, other = trees
    rng, monitor = problem.rng, problem.monitor
    while time.monotonic() < deadline:
        monitor.check()
        reached, _ = extend(grow, rng.uniform(lower, upper))
        meet, connected = extend(other, grow.nodes[reached])
        if connected:
            stats.nodes = len(trees[0]) + len(trees[1])
            a, b = (reached, meet) if grow is trees[0] else (meet, reached)
            return np.array(trees[0].branch(a) + trees[1].branch(b)[::-1][1:])
        grow, other = other, grow
    stats.nodes = len(trees[0]) + len(trees[1])
    raise errors.PlanningTimedOut(
        f"{PLANNER_ID} found no path on the path constraints within the time budget ({stats.nodes} nodes)",
        source="planner",
    )


register(ArmPlannerSpec(PLANNER_ID, DESCRIPTION, None, PARAMS, frozenset({"tree", "path_constraints"}), search=search))
