"""OMPL glue: a group's joint-limit box as a state space, a validity checker and a batched edge validator.

Motion resolution (the one number that decides what "collision-free edge" means): an edge
q_a → q_b is checked at ``n = ceil(max_i |q_b,i − q_a,i| / resolution)`` evenly spaced states
(q_a excluded, q_b included), i.e. no joint moves more than ``resolution`` radians between two
checked states (an L∞ step in joint space). All n states go to the checker in ONE call,
``checker.first_invalid(Q)``, so an edge costs one Python→checker round trip however long it is.
They are passed end state first, then in bisection order (midpoint, quarter points, …), like
OMPL's ``DiscreteMotionValidator``: a checker that stops at the first hit finds a blocked edge
after few states.

The checker protocol (any object with these methods works: the pinocchio/coal checker, the
sphere checker, the 2-D toy checkers of the tests): ``is_valid(q)``, ``first_invalid(Q)`` (index
of the first invalid row or -1), ``colliding_pairs(q)``, ``check_count`` and ``reset_count()``,
all on full robot configurations.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import geometric as og

from maru_planner.collision.kernels.bisection import bisection_order


class GroupSpace:
    """A planning group's joints as an OMPL ``RealVectorStateSpace`` bounded by the joint limits.

    ``base`` is the full robot configuration that supplies the joints outside the group.
    """

    def __init__(self, joint_names, indices, lower, upper, base):
        self.joint_names = list(joint_names)
        self.indices = np.asarray(indices, dtype=int)
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.base = np.asarray(base, dtype=float).copy()
        self.dim = len(self.joint_names)
        self._whole_robot = np.array_equal(self.indices, np.arange(len(self.base)))
        self.space = ob.RealVectorStateSpace(self.dim)
        bounds = ob.RealVectorBounds(self.dim)
        for i in range(self.dim):
            bounds.setLow(i, float(self.lower[i]))
            bounds.setHigh(i, float(self.upper[i]))
            self.space.setDimensionName(i, self.joint_names[i])
        self.space.setBounds(bounds)

    def to_array(self, state) -> np.ndarray:
        return np.array([state[i] for i in range(self.dim)])

    def to_state(self, q: np.ndarray | list[float], state: Any = None) -> Any:
        if state is None:
            state = self.space.allocState()
        for i in range(self.dim):
            state[i] = float(q[i])
        return state

    def full(self, q_group: np.ndarray) -> np.ndarray:
        """Full robot configuration(s) for group configuration(s) (1-D or rows)."""
        q_group = np.asarray(q_group, dtype=float)
        if q_group.ndim == 1:
            q = self.base.copy()
            q[self.indices] = q_group
            return q
        return q_group if self._whole_robot else full_configurations(self.base, self.indices, q_group)


def full_configurations(base: np.ndarray, indices, group_states: np.ndarray) -> np.ndarray:
    """One full configuration per row of ``group_states``: ``base`` with its ``indices`` set to that row."""
    out = np.repeat(np.asarray(base, dtype=float)[None], len(group_states), axis=0)
    out[:, indices] = group_states
    return out


def edge_states(qa: np.ndarray, qb: np.ndarray, resolution: float) -> np.ndarray:
    """States checked for the edge qa → qb at ``resolution`` (qa excluded, qb included)."""
    steps = max(1, math.ceil(float(np.abs(qb - qa).max()) / resolution))
    t = np.arange(1, steps + 1, dtype=float)[:, None] / steps
    return qa + t * (qb - qa)


class EdgeChecker:
    """Numpy-side validity of states, edges and paths of one group against a checker."""

    def __init__(self, group_space: GroupSpace, checker, resolution: float):
        if not resolution > 0:
            raise ValueError(f"motion resolution must be > 0, got {resolution}")
        self.gs = group_space
        self.checker = checker
        self.resolution = float(resolution)

    def edge_valid(self, qa: np.ndarray, qb: np.ndarray) -> bool:
        """True if every state of qa → qb (qa excluded) is free; one checker call, in bisection order."""
        states = edge_states(qa, qb, self.resolution)
        order = bisection_order(len(states), include_first=False)
        return int(self.checker.first_invalid(self.gs.full(states[order]))) < 0

    def path_valid(self, path: np.ndarray) -> bool:
        """All edges of ``path`` in one batched call (the start state is checked too)."""
        chunks = [path[:1]] + [edge_states(path[i], path[i + 1], self.resolution) for i in range(len(path) - 1)]
        return int(self.checker.first_invalid(self.gs.full(np.vstack(chunks)))) < 0


class BatchedMotionValidator(ob.MotionValidator):
    """OMPL motion validator: one ``checker.first_invalid`` call per edge (see module doc)."""

    def __init__(self, si, edge_checker: EdgeChecker):
        super().__init__(si)
        self.edges = edge_checker
        self._gs = edge_checker.gs

    def checkMotion(self, s1: Any, s2: Any, *_: Any) -> bool:  # noqa: N802 (OMPL's name)
        return self.edges.edge_valid(self._gs.to_array(s1), self._gs.to_array(s2))


def make_validity_fn(edge_checker: EdgeChecker) -> Callable[[Any], bool]:
    """A Python state-validity callable for ``SpaceInformation.setStateValidityChecker``."""
    gs = edge_checker.gs
    checker = edge_checker.checker
    dim = gs.dim

    def is_valid(state) -> bool:
        return bool(checker.is_valid(gs.full(np.array([state[i] for i in range(dim)]))))

    return is_valid


class GroupSetup:
    """A group's space and an OMPL ``SimpleSetup`` on it whose space information is set up once, then reused.

    Setting up OMPL's SpaceInformation (the state space, its projections) costs more than a trivial
    search, so a planner keeps one GroupSetup per group and, per search, calls :meth:`prepare` with the
    request's ``base`` (the joints outside the group) and motion resolution, then plugs in a fresh
    planner. Built before the search's seeded section, so OMPL's seed generator gives a search the same
    numbers whether its setup is new or reused.
    """

    def __init__(self, group_space: GroupSpace, checker, resolution: float):
        self.gs = group_space
        self.edges = EdgeChecker(group_space, checker, resolution)
        self.ss = og.SimpleSetup(group_space.space)
        self.ss.setStateValidityChecker(make_validity_fn(self.edges))
        si = self.ss.getSpaceInformation()
        self._validator = BatchedMotionValidator(si, self.edges)  # lives as long as the setup
        si.setMotionValidator(self._validator)
        si.setup()

    def prepare(self, base: np.ndarray, resolution: float) -> None:
        """Use ``base`` for the joints outside the group and check motions every ``resolution`` rad."""
        if not resolution > 0:
            raise ValueError(f"motion resolution must be > 0, got {resolution}")
        self.gs.base = np.asarray(base, dtype=float).copy()
        self.edges.resolution = float(resolution)
        self.ss.clear()  # the previous search's planner data and solutions
