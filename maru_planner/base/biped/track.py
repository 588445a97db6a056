"""Track following (paper 004, §2.2): the robot centre follows the mid-line between obstacles.

The track is the pruned Voronoi diagram of the obstacle cells' centres (the
points equidistant from two obstacles), keeping only ridges whose two
generating points are at least ``w_k`` apart and whose clearance fits half the
gait width. The shortest track from start to goal is simplified to straight
segments; at each segment point the robot turns in place about its centre
by φ (the heading change), allowed when (eq. 4 and Fig. 4–5):

* φ ≥ π/2:  K ≤ L
* φ < π/2:  K·sin θ ≤ L, with θ = min(φ + atan(w_k / l), π/2) the largest
  angle between a corner's diagonal and the passage during the turn

where K is the centre-to-corner distance of the gait rectangle and L half the
passage width (the clearance of the mid-line there). A segment point that
fails is removed from the track graph and the next shortest track is tried
(``max_reroutes`` times); the whole motion is finally swept with the
rectangle as a safety check.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import Voronoi, cKDTree

from maru_planner.base.biped.mapping import BipedMap2D
from maru_planner.base.biped.space import BipedPlanner, BipedSpace, BipedStats
from maru_planner.base.biped.world import BipedRobot
from maru_planner.base.budget import Deadline
from maru_planner.base.common import wrap_angle
from maru_planner.base.planner import Endpoint, PlanRun
from maru_planner.errors import InvalidRequest, NoPath, TooLarge
from maru_planner.params import param

# Qhull cannot be interrupted: more obstacle-boundary points than this are refused up front.
MAX_VORONOI_POINTS = 100_000
_VORONOI_SECONDS_PER_POINT = 1e-4  # a generous Qhull time per point (about 2e-5 s measured on a loaded machine)


@dataclass
class TrackParams:
    max_reroutes: int = param(20, "other tracks tried after a refused turn", lower=0, upper=10000)
    connect_radius: float = param(3.0, "how far start and goal look for the track (m)", lower=1e-3)
    simplify_tolerance: float | None = param(None, "Douglas-Peucker tolerance (m); default one cell", lower=0.0)

    def validate(self) -> None:
        if self.max_reroutes < 0 or not self.connect_radius > 0:
            raise InvalidRequest("max_reroutes must be >= 0 and connect_radius > 0")
        if self.simplify_tolerance is not None and not self.simplify_tolerance >= 0:
            raise InvalidRequest("simplify_tolerance must be >= 0 m")


@dataclass
class TrackStats(BipedStats):
    reroutes: int = 0


def turn_allowed(phi: float, robot: BipedRobot, half_width: float) -> tuple[bool, float]:
    """The paper's turning rule; returns (allowed, the K or K·sin θ that was compared with L)."""
    k = robot.corner_distance
    phi = abs(phi)
    if phi >= math.pi / 2:
        need = k
    else:
        theta = min(phi + math.atan2(robot.gait_width, robot.gait_length), math.pi / 2)
        need = k * math.sin(theta)
    return need <= half_width + 1e-9, need


def _boundary_points(m: BipedMap2D) -> np.ndarray:
    occ = m.occupied
    padded = np.pad(occ, 1, constant_values=True)
    free_nb = np.zeros_like(padded)
    free_nb[1:-1, 1:-1] = ~padded[:-2, 1:-1] | ~padded[2:, 1:-1] | ~padded[1:-1, :-2] | ~padded[1:-1, 2:]
    boundary = padded & free_nb  # includes a ring of border cells just outside the map
    rows, cols = np.nonzero(boundary)
    r = m.resolution
    return np.column_stack([m.origin[0] + (cols - 1 + 0.5) * r, m.origin[1] + (rows - 1 + 0.5) * r])


class ClearanceLookup:
    """Clearance of a map's cells (capped at ``cap`` metres) looked up at points and along segments."""

    def __init__(self, m: BipedMap2D, cap: float = math.inf, deadline: Deadline | None = None):
        self.m = m
        self.values = m.clearance(cap, deadline)

    def at(self, pts: np.ndarray) -> np.ndarray:
        pts = np.asarray(pts, dtype=float).reshape(-1, 2)
        cols = np.floor((pts[:, 0] - self.m.origin[0]) / self.m.resolution).astype(int)
        rows = np.floor((pts[:, 1] - self.m.origin[1]) / self.m.resolution).astype(int)
        h, w = self.values.shape
        inside = (rows >= 0) & (cols >= 0) & (rows < h) & (cols < w)
        out = np.zeros(len(pts))
        out[inside] = self.values[rows[inside], cols[inside]]
        return out

    def segment_min(self, a, b) -> float:
        n = max(2, int(math.ceil(math.dist(a, b) / (self.m.resolution / 2))) + 1)
        t = np.linspace(0, 1, n)[:, None]
        return float(self.at(np.asarray(a) + t * (np.asarray(b) - np.asarray(a))).min())


def build_track_graph(m: BipedMap2D, robot: BipedRobot, clearance: ClearanceLookup, deadline: Deadline):
    """Pruned Voronoi mid-lines: (vertices (n, 2), adjacency dict i -> {j: length})."""
    pts = _boundary_points(m)
    half = robot.gait_width / 2
    if len(pts) < 4:
        return np.zeros((0, 2)), {}
    if len(pts) > MAX_VORONOI_POINTS:
        raise TooLarge(
            f"the map has {len(pts)} obstacle-boundary points, over the track planner's limit of "
            f"{MAX_VORONOI_POINTS}: use a coarser map"
        )
    # Qhull cannot be interrupted: start it only with time to finish
    deadline.reserve(len(pts) * _VORONOI_SECONDS_PER_POINT, f"the Voronoi diagram of {len(pts)} points")
    vor = Voronoi(pts)
    deadline.check_now("building the track graph")
    verts = vor.vertices
    vclear = clearance.at(verts)
    adjacency: dict = {}
    for (pi, pj), (va, vb) in zip(vor.ridge_points, vor.ridge_vertices):
        deadline.check_now("building the track graph")
        if va < 0 or vb < 0 or va == vb:
            continue
        if np.linalg.norm(pts[pi] - pts[pj]) < robot.gait_width + m.resolution:
            continue
        if vclear[va] < half or vclear[vb] < half:
            continue
        if clearance.segment_min(verts[va], verts[vb]) < half:
            continue
        length = float(np.linalg.norm(verts[va] - verts[vb]))
        adjacency.setdefault(va, {})[vb] = length
        adjacency.setdefault(vb, {})[va] = length
    return verts, adjacency


def _shortest(adjacency: dict, source, target, banned: set):
    dist = {source: 0.0}
    prev: dict = {}
    heap = [(0.0, source)]
    while heap:
        d, u = heapq.heappop(heap)
        if u == target:
            path = [u]
            while u in prev:
                u = prev[u]
                path.append(u)
            return path[::-1]
        if d > dist[u]:
            continue
        for v, w in adjacency.get(u, {}).items():
            if v in banned:
                continue
            nd = d + w
            if nd < dist.get(v, math.inf):
                dist[v] = nd
                prev[v] = u
                heapq.heappush(heap, (nd, v))
    return None


def douglas_peucker(points: np.ndarray, tol: float) -> np.ndarray:
    if len(points) <= 2:
        return points
    a, b = points[0], points[-1]
    ab = b - a
    norm = np.linalg.norm(ab)
    if norm < 1e-12:
        d = np.linalg.norm(points - a, axis=1)
    else:
        d = np.abs(ab[0] * (points[:, 1] - a[1]) - ab[1] * (points[:, 0] - a[0])) / norm
    i = int(np.argmax(d))
    if d[i] <= tol:
        return np.array([a, b])
    left = douglas_peucker(points[: i + 1], tol)
    right = douglas_peucker(points[i:], tol)
    return np.vstack([left[:-1], right])


class TrackFollowingPlanner(BipedPlanner):
    """Track following on a :class:`BipedMap2D` for a :class:`BipedRobot`."""

    def __init__(self, robot: BipedRobot, params: TrackParams | None = None, **overrides):
        self.robot = robot
        unknown = set(overrides) - {f.name for f in dataclasses.fields(TrackParams)}
        if unknown:
            raise InvalidRequest(f"unknown biped_track parameter(s) {sorted(unknown)}")
        self.params = dataclasses.replace(params or TrackParams(), **overrides)
        self.params.validate()

    def new_stats(self) -> BipedStats:
        return TrackStats(deciding_stage="track")

    def search(self, space: BipedSpace, start_end: Endpoint, goal_end: Endpoint, run: PlanRun) -> np.ndarray:
        try:
            return self._search(space.map, space.checker, start_end.pose, goal_end.pose, run)
        finally:
            run.stats.collision_checks = space.checker.checks

    def _search(self, m: BipedMap2D, checker, start, goal, run: PlanRun) -> np.ndarray:
        robot, p, stats, layers = self.robot, self.params, run.stats_as(TrackStats), run.layers
        # the turning rule and the gait width never ask for more than K (+ a cell)
        clearance = ClearanceLookup(m, robot.corner_distance + m.resolution, run.deadline)
        verts, adjacency = build_track_graph(m, robot, clearance, run.deadline)
        layers["track_vertices"], layers["track_edges"] = verts, _edge_array(verts, adjacency)
        half = robot.gait_width / 2
        s_id, g_id = len(verts), len(verts) + 1
        nodes = (
            np.vstack([verts, np.asarray(start[:2], float), np.asarray(goal[:2], float)])
            if len(verts)
            else np.array([start[:2], goal[:2]], dtype=float)
        )
        if not len(verts):
            s_id, g_id = 0, 1
        graph = {k: dict(v) for k, v in adjacency.items()}
        self._connect(graph, nodes, s_id, clearance, half, verts)
        self._connect(graph, nodes, g_id, clearance, half, verts)
        if clearance.segment_min(start[:2], goal[:2]) >= half:
            length = math.dist(start[:2], goal[:2])
            graph.setdefault(s_id, {})[g_id] = length
            graph.setdefault(g_id, {})[s_id] = length
        banned: set = set()
        message = "no mid-line track joins start and goal with room for the gait width"
        for attempt in range(p.max_reroutes + 1):
            stats.reroutes = attempt
            run.deadline.check_now("track following")
            ids = _shortest(graph, s_id, g_id, banned)
            stats.expansions += len(ids or ())
            if ids is None:
                break
            track = self._simplify(nodes[ids], clearance, half, m.resolution)
            layers["track"] = track
            failure = self._check_turns(track, start, goal, clearance)
            if failure is None:
                poses = _poses(track, start, goal)
                if not checker.sweep_collides(poses, m.resolution / 2):
                    run.message = f"track found ({len(track) - 1} segments)"
                    return poses
                failure = (1, "the turning rule passed but the gait rectangle's sweep collides")
            index, message = failure
            if index in (0, len(track) - 1):
                break  # turning at the start or the goal cannot be avoided by another route
            near = cKDTree(verts).query_ball_point(track[index], r=max(robot.corner_distance, 2 * m.resolution))
            banned.update(near)
        raise NoPath(message)

    def _connect(self, graph, nodes, node_id, clearance, half, verts):
        if not len(verts):
            return
        tree = cKDTree(verts)
        here = nodes[node_id]
        candidates = tree.query_ball_point(here, r=self.params.connect_radius)
        candidates = sorted(candidates, key=lambda i: (float(np.linalg.norm(verts[i] - here)), i))
        linked = 0
        for i in candidates:
            if i not in graph:
                continue
            if clearance.segment_min(here, verts[i]) >= half:
                length = float(np.linalg.norm(verts[i] - here))
                graph.setdefault(node_id, {})[i] = length
                graph.setdefault(i, {})[node_id] = length
                linked += 1
                if linked >= 6:
                    break

    def _simplify(self, points, clearance, half, resolution):
        tol = self.params.simplify_tolerance or resolution
        while tol >= resolution / 8:
            track = douglas_peucker(points, tol)
            if all(clearance.segment_min(a, b) >= half for a, b in zip(track[:-1], track[1:])):
                return track
            tol /= 2
        return points

    def _check_turns(self, track, start, goal, clearance):
        """Index and message of the first segment point where the turn is not allowed, or None."""
        headings = [
            math.atan2(b[1] - a[1], b[0] - a[0]) for a, b in zip(track[:-1], track[1:]) if np.linalg.norm(b - a) > 1e-9
        ]
        if not headings:
            headings = [start[2]]
        turns = [(0, wrap_angle(headings[0] - start[2]))]
        turns += [(i + 1, wrap_angle(headings[i + 1] - headings[i])) for i in range(len(headings) - 1)]
        turns.append((len(track) - 1, wrap_angle(goal[2] - headings[-1])))
        for index, phi in turns:
            if abs(phi) < 1e-9:
                continue
            half_width = float(clearance.at(track[index])[0])
            ok, need = turn_allowed(phi, self.robot, half_width)
            if not ok:
                x, y = track[index]
                return index, (
                    f"turn of {math.degrees(abs(phi)):.0f} deg at ({x:.2f}, {y:.2f}) needs "
                    f"{need:.3f} m <= L = {half_width:.3f} m (K = {self.robot.corner_distance:.3f} m)"
                )
        return None


def _edge_array(verts, adjacency) -> np.ndarray:
    edges = [(verts[a], verts[b]) for a, nbs in adjacency.items() for b in nbs if a < b]
    return np.asarray(edges, dtype=float).reshape(-1, 2, 2)


def _poses(track: np.ndarray, start, goal) -> np.ndarray:
    """Turn in place at each segment point, then walk the segment."""
    poses = [tuple(start)]
    heading = start[2]
    for a, b in zip(track[:-1], track[1:]):
        if np.linalg.norm(b - a) <= 1e-9:
            continue
        new = math.atan2(b[1] - a[1], b[0] - a[0])
        if abs(wrap_angle(new - heading)) > 1e-9:
            poses.append((a[0], a[1], new))
        poses.append((b[0], b[1], new))
        heading = new
    if abs(wrap_angle(goal[2] - heading)) > 1e-9 or len(poses) == 1:
        poses.append((goal[0], goal[1], goal[2]))
    out = np.asarray(poses, dtype=float)
    out[:, 2] = np.unwrap(out[:, 2])
    out[:, 2] = [wrap_angle(t) for t in out[:, 2]]
    return out
