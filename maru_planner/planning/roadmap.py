"""A persistent OMPL PRM roadmap: built once, queried many times while the scene is unchanged.

The paper's complaint about PRM is that the roadmap must be rebuilt whenever an obstacle moves.
Here a roadmap remembers the scene it was built in. After a scene change the MotionPlanner keeps
using it but checks each answer against the current scene (one batched call); only when an answer
is blocked does it re-validate the whole roadmap (:meth:`Roadmap.revalidate`: two batched checker
calls, all milestones then all edge states at the motion resolution, timed) and rebuild it if
anything died (OMPL's PRM offers no way to delete milestones or edges from Python). New
milestones and edges added after the change are always checked in the current scene.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from ompl import base as ob
from ompl import geometric as og

from maru_planner.planning.space import (
    BatchedMotionValidator,
    EdgeChecker,
    GroupSpace,
    edge_states,
    make_validity_fn,
)


@dataclass
class RevalidationReport:
    """What re-validating a roadmap against a new scene cost and found."""

    seconds: float
    vertices: int
    edges: int
    states_checked: int
    invalid_vertices: int
    invalid_edges: int

    @property
    def still_valid(self) -> bool:
        return self.invalid_vertices == 0 and self.invalid_edges == 0


class Roadmap:
    """One group's PRM (OMPL ``PRM``) with its own SimpleSetup, kept between queries."""

    def __init__(self, group_space: GroupSpace, checker, resolution: float, max_nearest_neighbors: int = 3):
        self.gs = group_space
        self.edges = EdgeChecker(group_space, checker, resolution)
        self.ss = og.SimpleSetup(group_space.space)
        self.si = self.ss.getSpaceInformation()
        self.ss.setStateValidityChecker(make_validity_fn(self.edges))
        self._validator = BatchedMotionValidator(self.si, self.edges)
        self.si.setMotionValidator(self._validator)
        self.planner = og.PRM(self.si)
        self.planner.setMaxNearestNeighbors(int(max_nearest_neighbors))
        self.ss.setPlanner(self.planner)
        self.scene_epoch = -1
        self.build_time = 0.0
        self.queries = 0

    @property
    def milestones(self) -> int:
        return int(self.planner.milestoneCount())

    @property
    def edge_count(self) -> int:
        return int(self.planner.edgeCount())

    def build(self, nodes: int, deadline: float) -> float:
        """Grow the roadmap until it has ``nodes`` milestones or ``deadline`` (monotonic) passes."""
        self.ss.setup()
        t0 = time.monotonic()

        def done() -> bool:
            return self.planner.milestoneCount() >= nodes or time.monotonic() >= deadline

        if not done():
            self.planner.constructRoadmap(ob.PlannerTerminationCondition(done))
        self.build_time += time.monotonic() - t0
        return self.build_time

    def query(self, start: np.ndarray, goal: np.ndarray, seconds: float):
        """Solve start→goal on the roadmap (it may keep growing while searching). Returns (status, path|None)."""
        self.planner.clearQuery()
        self.ss.getProblemDefinition().clearSolutionPaths()
        self.ss.setStartAndGoalStates(self.gs.to_state(start), self.gs.to_state(goal))
        status = self.ss.solve(ob.timedPlannerTerminationCondition(max(seconds, 1e-3)))
        self.queries += 1
        if not self.ss.haveExactSolutionPath():
            return status, None
        states = self.ss.getSolutionPath().getStates()
        return status, np.array([self.gs.to_array(s) for s in states])

    def graph(self):
        """(vertices as an (n, dim) array, undirected edges as an (m, 2) index array)."""
        data = ob.PlannerData(self.si)
        self.planner.getPlannerData(data)
        n = data.numVertices()
        verts = np.array([self.gs.to_array(data.getVertex(i).getState()) for i in range(n)]).reshape(n, self.gs.dim)
        pairs = {(min(i, j), max(i, j)) for i in range(n) for j in data.getEdges(i) if i != j}
        return verts, np.array(sorted(pairs), dtype=int).reshape(-1, 2)

    def revalidate(self) -> RevalidationReport:
        """Check every milestone and edge against the checker's current scene (batched)."""
        t0 = time.monotonic()
        verts, edges = self.graph()
        checker = self.edges.checker
        vertex_ok = np.asarray(checker.are_valid(self.gs.full(verts)), dtype=bool) if len(verts) else np.ones(0, bool)
        states_checked = len(verts)
        invalid_edges = 0
        if len(edges):
            chunks = [edge_states(verts[a], verts[b], self.edges.resolution) for a, b in edges]
            sizes = np.array([len(c) for c in chunks])
            ok = np.asarray(checker.are_valid(self.gs.full(np.vstack(chunks))), dtype=bool)
            states_checked += int(sizes.sum())
            starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
            edge_ok = np.logical_and.reduceat(ok, starts)
            invalid_edges = int((~edge_ok).sum())
        return RevalidationReport(
            seconds=time.monotonic() - t0,
            vertices=len(verts),
            edges=len(edges),
            states_checked=states_checked,
            invalid_vertices=int((~vertex_ok).sum()),
            invalid_edges=invalid_edges,
        )
