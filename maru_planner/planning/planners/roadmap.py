"""A persistent OMPL PRM roadmap: built once, queried many times while the scene is unchanged.

The paper's complaint about PRM is that the roadmap must be rebuilt whenever an obstacle moves.
Here a roadmap remembers the scene it was built in. After a scene change the MotionPlanner keeps
using it but checks each answer against the current scene (one batched call); only when an answer
is blocked does it re-validate the whole roadmap (:meth:`Roadmap.revalidate`: two batched checker
calls, all milestones then all edge states at the motion resolution, timed) and rebuild it if
anything died (OMPL's PRM offers no way to delete milestones or edges from Python). New
milestones and edges added after the change are always checked in the current scene.

Growth is deterministic: OMPL's ``PRM.constructRoadmap`` switches between growing and expanding
the roadmap every 0.2–0.4 s of wall time and ``PRM.solve`` grows it in a second thread, so the
roadmap (and the path) would depend on timing. Here the roadmap grows in the calling thread,
alternating the same two OMPL phases by milestone counts (two parts growing, one expanding, as
OMPL's time ratio): with OMPL seeded, the same seed builds the same roadmap, and the same query on
it gives the same path.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

from maru_planner.planning.planners.registry import RoadmapPlanner, make_planner
from maru_planner.planning.space import (
    BatchedMotionValidator,
    EdgeChecker,
    GroupSpace,
    edge_states,
    make_validity_fn,
)

#: Milestones added per grow/expand round (grow 2·, expand 1·) and, at least, per growth step of a query.
GROWTH_CHUNK = 30
#: Termination-condition polls one phase may use per milestone it should add (bounds a phase that adds nothing).
_POLLS_PER_MILESTONE = 50


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
    """One group's roadmap (a "roadmap" planner of the registry, OMPL ``PRM`` by default), kept between queries."""

    def __init__(
        self, group_space: GroupSpace, checker, resolution: float, planner_id: str = "PRM", params: dict | None = None
    ):
        self.gs = group_space
        self.edges = EdgeChecker(group_space, checker, resolution)
        self.ss = og.SimpleSetup(group_space.space)
        self.si = self.ss.getSpaceInformation()
        self.ss.setStateValidityChecker(make_validity_fn(self.edges))
        self._validator = BatchedMotionValidator(self.si, self.edges)
        self.si.setMotionValidator(self._validator)
        self.planner: RoadmapPlanner = make_planner(planner_id, self.si, params, self.edges)  # type: ignore[assignment]
        self.ss.setPlanner(self.planner)
        self.scene_epoch: tuple | None = None  # the MotionPlanner's scene key when the roadmap was built
        self.build_time = 0.0
        self.queries = 0
        self._graph_cache = None

    @property
    def milestones(self) -> int:
        return int(self.planner.milestoneCount())

    @property
    def edge_count(self) -> int:
        return int(self.planner.edgeCount())

    def build(self, nodes: int, deadline: float) -> None:
        """Grow the roadmap until it has ``nodes`` milestones or ``deadline`` (monotonic) passes."""
        self.ss.setup()
        t0 = time.monotonic()
        while self.milestones < nodes and time.monotonic() < deadline:
            self._grow_round(nodes, deadline)
        self.build_time += time.monotonic() - t0

    def _grow_round(self, nodes: int, deadline: float) -> None:
        """A grow phase (2·GROWTH_CHUNK milestones) then an expand phase (GROWTH_CHUNK), capped at ``nodes``."""
        self._phase(self.planner.growRoadmapPtc, min(nodes, self.milestones + 2 * GROWTH_CHUNK), deadline)
        self._phase(self.planner.expandRoadmapPtc, min(nodes, self.milestones + GROWTH_CHUNK), deadline)

    def _phase(self, run, target: int, deadline: float) -> None:
        """Run OMPL phase ``run`` until ``target`` milestones, its poll budget or ``deadline`` (the only clock)."""
        polls = _POLLS_PER_MILESTONE * max(1, target - self.milestones)

        def done() -> bool:
            nonlocal polls
            polls -= 1
            return polls < 0 or self.planner.milestoneCount() >= target or time.monotonic() >= deadline

        if not done():
            run(ob.PlannerTerminationCondition(done))

    def query(self, start: np.ndarray, goal: np.ndarray, seconds: float) -> tuple[str, np.ndarray | None]:
        """Solve start→goal on the roadmap. Returns (mode, path | None).

        First the query phase on the roadmap as it is (:meth:`query_graph`): mode "roadmap". If start
        and goal cannot be attached to one connected component, the roadmap grows (a quarter of its
        size, at least ``GROWTH_CHUNK`` milestones, per step) and is queried again until they can or
        ``seconds`` run out: mode "grow".
        """
        self.queries += 1
        path = self.query_graph(start, goal)
        if path is not None:
            return "roadmap", path
        self.ss.setup()
        deadline = time.monotonic() + seconds
        while path is None and time.monotonic() < deadline:
            target = self.milestones + max(GROWTH_CHUNK, self.milestones // 4)
            while self.milestones < target and time.monotonic() < deadline:
                self._grow_round(target, deadline)
            path = self.query_graph(start, goal)
        return "grow", path

    def _search_graph(self):
        """Vertices, k-d tree, sparse edge-length graph and components of the roadmap (cached per size)."""
        key = (self.milestones, self.edge_count)
        if self._graph_cache is None or self._graph_cache[0] != key:
            verts, edges = self.graph()
            n = len(verts)
            lengths = np.linalg.norm(verts[edges[:, 0]] - verts[edges[:, 1]], axis=1) if len(edges) else np.zeros(0)
            adj = csr_matrix((lengths, (edges[:, 0], edges[:, 1])), shape=(n, n)) if n else None
            _, comp = connected_components(adj, directed=False) if n else (0, np.zeros(0, int))
            tree = cKDTree(verts) if n else None
            self._graph_cache = (key, verts, adj, comp, tree)
        return self._graph_cache[1:]

    def query_graph(self, start: np.ndarray, goal: np.ndarray, candidates: int = 8) -> np.ndarray | None:
        """PRM query phase: attach start and goal to their nearest reachable milestones of one
        component (batched edge checks, nearest first) and run Dijkstra on the roadmap."""
        verts, adj, comp, tree = self._search_graph()
        if tree is None or len(verts) < 2:
            return None
        k = min(candidates, len(verts))
        s_near = np.atleast_1d(tree.query(start, k=k)[1])
        g_near = np.atleast_1d(tree.query(goal, k=k)[1])
        s_ok: dict[int, bool] = {}
        g_ok: dict[int, bool] = {}
        for a in s_near:  # nearest pairs first; each edge is checked at most once
            for b in g_near:
                if comp[a] != comp[b]:
                    continue
                if a not in s_ok:
                    s_ok[a] = self.edges.edge_valid(start, verts[a])
                if not s_ok[a]:
                    break
                if b not in g_ok:
                    g_ok[b] = self.edges.edge_valid(verts[b], goal)
                if g_ok[b]:
                    return self._shortest(verts, adj, int(a), int(b), start, goal)
        return None

    @staticmethod
    def _shortest(verts, adj, a: int, b: int, start, goal):
        _, pred = dijkstra(adj, directed=False, indices=a, return_predecessors=True)
        chain = [b]
        while chain[-1] != a:
            chain.append(int(pred[chain[-1]]))
        return np.vstack([start, verts[chain[::-1]], goal])

    def graph(self) -> tuple[np.ndarray, np.ndarray]:
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
