"""PathCertifier: certified collision-free arm paths, continuous validation of straight joint-space segments (the
package doc, :mod:`maru_planner.collision.certify`, describes the method)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import coal
import numpy as np
import pinocchio as pin

from maru_planner import errors
from maru_planner.collision.certify.bounds import (
    MEASURE_BOUND,
    MEASURE_EXACT,
    MEASURE_NONE,
    assess_rows_nb,
    poses_nb,
    proves_too_little,
    volume_bounds_nb,
)
from maru_planner.collision.certify.cover import DISTANCE_TOLERANCE, NO_COVER, SphereCover
from maru_planner.collision.certify.levers import (
    PRISMATIC,
    bounding_sphere,
    downstream_levers,
    joint_levers,
    joint_of_q,
)
from maru_planner.collision.certify.pairs import PairTable, bounding_box, box_distances, kernel_primitives
from maru_planner.collision.certify.rounds import (
    MAX_SPLIT,
    MIN_INTERVAL,
    CertificationRun,
    finish_round_nb,
    round_configs_nb,
)
from maru_planner.collision.checker import CollisionChecker, hull_or_self, robot_hull, self_collision_pairs
from maru_planner.collision.kernels.support_bounds import HULL, NO_SHAPE
from maru_planner.collision.kinematic_tree import KinematicTree, tree_arrays
from maru_planner.collision.shape_records import robot_shape_records
from maru_planner.collision.sphere_model import SphereModel
from maru_planner.robot.model import RobotModel
from maru_planner.scene import Obstacle, Scene

DEFAULT_SAFETY_MARGIN = 0.01  # m (PlannerConfig.safety_margin's default too)
SHARED_END = 1e-12  # rad: a segment's rest between its blends this short is their shared end (certify_path)
NEAR_PATH_MIN_OBSTACLES = 64  # reachable obstacles from which a certification only builds pairs for those near its path
NEAR_TABLES = 4  # pair tables of near obstacles kept (blends and repairs certify around the same path)
CLEARANCE_WINDOW = 0.05  # m: clearance() measures the obstacles whose bound is this close to the nearest one first


@dataclass
class Certificate:
    """Whether a piecewise-linear path keeps more than ``margin`` (m) from every checked pair, and its cost.

    ``reason`` of a failure: "collision" (the exact geometry overlaps at ``witness``), "margin" (closer than
    the margin at ``witness``), "unproven" (a piece shorter than ``MIN_INTERVAL`` stayed unproven) or
    "timeout". ``min_clearance`` is the smallest distance bound seen at a checked configuration (exact
    where the bounding volumes were not enough): the path's true minimum lies between ``margin`` and it.
    """

    valid: bool
    margin: float
    first_failing_segment: int = -1
    reason: str = ""
    witness: np.ndarray | None = None
    min_clearance: float = math.inf
    segment_clearance: list[float] = field(default_factory=list)  # min_clearance of each certified segment
    checks: int = 0  # configurations evaluated
    exact_queries: int = 0  # coal distance calls on the exact geometry
    hull_queries: int = 0  # coal distance calls on convex hulls of meshes
    seconds: float = 0.0


def without_corners(path: np.ndarray, corner_blends: np.ndarray) -> np.ndarray:
    """Each segment of ``path`` without its ends within ``corner_blends`` of its waypoints (at most all of it), as
    consecutive (start, end) rows."""
    delta = np.diff(path, axis=0)
    length = np.linalg.norm(delta, axis=1)
    unit = np.divide(delta, length[:, None], out=np.zeros_like(delta), where=length[:, None] > 0.0)
    head = np.minimum(corner_blends[:-1], length)
    tail = np.minimum(corner_blends[1:], length - head)
    out = np.empty((2 * len(delta), path.shape[1]))
    out[0::2] = path[:-1] + head[:, None] * unit
    out[1::2] = path[1:] - tail[:, None] * unit
    return out


class PathCertifier:
    """Certifies straight joint-space segments and paths on the exact checker's geometry (package doc).

    ``scene_or_checker``: a :class:`CollisionChecker` (its scene and pairs are followed as they change)
    or a :class:`Scene` (an exact checker is built on it). ``safety_margin`` (m, >= 0): the clearance a
    certified path keeps from every checked pair. ``spheres``: a sphere model of ``robot`` (the search's)
    whose cover of its meshes tightens their bounds (:class:`~.cover.SphereCover`). Not thread-safe (one Pinocchio
    ``Data``).
    """

    def __init__(
        self, robot: RobotModel, scene_or_checker: CollisionChecker | Scene | None = None,
        safety_margin: float = DEFAULT_SAFETY_MARGIN, spheres: SphereModel | None = None,
    ):  # fmt: skip
        if not (math.isfinite(safety_margin) and safety_margin >= 0.0):
            raise errors.InvalidRequest(f"safety_margin must be a finite number >= 0 m, got {safety_margin}")
        if isinstance(scene_or_checker, CollisionChecker):
            self.checker = scene_or_checker
        else:
            self.checker = CollisionChecker(robot, scene_or_checker, broadphase="none")
        self.robot = robot
        self.safety_margin = float(safety_margin)
        self._model = robot.model
        self._data = robot.model.createData()
        self._levers = joint_levers(robot)
        geometries = robot.collision_model.geometryObjects
        self._n_robot = len(geometries)
        enclosing = [bounding_sphere(obj.geometry) for obj in geometries]
        meshes = [g for g, obj in enumerate(geometries) if isinstance(obj.geometry, coal.BVHModelBase)]
        self._hulls = {g: robot_hull(geometries[g].geometry) for g in meshes}
        self._joint = np.array([obj.parentJoint for obj in geometries], dtype=int)
        self._local = np.array([obj.placement.act(c) for obj, (c, _) in zip(geometries, enclosing, strict=True)])
        self._radius = np.array([r for _, r in enclosing])
        self._chain = self._levers > 0.0
        self._tree = tree_arrays(KinematicTree.from_pinocchio(robot.model))
        self._q_joint = np.array([joint_of_q(robot.model, i) for i in range(robot.nq)], dtype=np.int64)
        self._prismatic = np.array([robot.model.joints[int(j)].shortname() in PRISMATIC for j in self._q_joint])
        self._downstream = downstream_levers(robot, self._levers)
        self._robot_pairs = self_collision_pairs(robot)
        self._geoms = self._robot_geometry(lambda g: geometries[g].geometry)
        self._hull_geoms = self._robot_geometry(lambda g: self._hulls.get(g, geometries[g].geometry))
        self._query = (coal.DistanceRequest(), coal.DistanceResult())  # reused (cleared): making them costs like GJK
        self._pairs: PairTable | None = None
        self._pairs_owner: list | None = None  # the reachable-obstacle list _pairs was built from
        self._near_tables: dict[bytes, PairTable] = {}  # by the near obstacles' indices into _near_owner
        self._near_owner: list | None = None
        self._boxes: tuple[list, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        self._moving = self._joint != 0
        self._cover = SphereCover.of(robot, spheres)
        self._robot_arrays = (*self._tree, self._joint, self._local, self._radius, self._q_joint, self._levers,
                              self._prismatic)  # fmt: skip
        self._cover_arrays = self._cover.arrays if self._cover is not None else NO_COVER
        self._shape_arrays = robot_shape_records(geometries, self._hulls)
        # Compile (or load from numba's cache) the kernels now: inside the first request it took ~1.5 s of its budget.
        self._centers(np.asarray(robot.neutral(), dtype=float)[None])
        self._warm_row_kernel()

    # ---------------------------------------------------------------- public --
    def certify_segment(
        self, q0: np.ndarray, q1: np.ndarray, deadline: float | None = None, *, margin: float | None = None
    ) -> Certificate:
        """Certify the straight segment ``q0 -> q1`` (full configurations)."""
        return self.certify_path(np.array([q0, q1], dtype=float), deadline, margin=margin)

    def certify_path(
        self,
        path: np.ndarray,
        deadline: float | None = None,
        *,
        margin: float | None = None,
        deviation: np.ndarray | None = None,
        corner_blends: np.ndarray | None = None,
    ) -> Certificate:
        """Certify every segment of ``path`` (n, nq full configurations); reports the first failing one.

        ``margin`` overrides ``safety_margin``. ``deviation`` (nq,): per joint, how far the real motion may
        leave the straight segments (a sampled curve: :func:`chord_deviation`); each pair's margin grows
        by the motion that deviation can cause. ``corner_blends`` (n,): per waypoint, how far along each of its
        segments (rad) a curve proven elsewhere replaces the path (a trajectory's blend): those ends (a segment
        two blends take whole: all of it) are left out.
        ``deadline`` (``time.monotonic()``): a certification still running then fails with reason "timeout".
        """
        t0 = time.monotonic()
        path = np.atleast_2d(np.asarray(path, dtype=float))
        margin = self.safety_margin if margin is None else float(margin)
        deviation = np.zeros(self._model.nq) if deviation is None else np.abs(np.asarray(deviation, dtype=float))
        n_segments = max(len(path) - 1, 0)
        points, curve, stride = path, np.zeros(n_segments, int), 1
        if corner_blends is not None and np.any(np.asarray(corner_blends) > 0.0) and n_segments:
            points, stride = without_corners(path, np.asarray(corner_blends, dtype=float)), 2
            curve = np.zeros(2 * n_segments - 1, int)
            curve[1::2] = -1  # between two trimmed segments: a blend, not this certification's
            # A segment its blends take whole leaves a point where they meet, proven with them (the rounding gap
            # moves no body by 1e-11 m, far within the DISTANCE_TOLERANCE every bound gives away)
            taken = np.linalg.norm(points[1::2] - points[0::2], axis=1) <= SHARED_END
            curve[0::2][taken] = -1
        cert, run = self._certify(points, np.tile(deviation, (len(curve), 1)), curve, margin, deadline)
        kept = run.clearance[::stride]  # per segment of ``path``
        failed = n_segments
        if run.failed < run.n_segments:
            failed = run.failed // stride
            cert.valid, cert.first_failing_segment = False, failed
            cert.reason, cert.witness = run.reason, run.witness
        cert.segment_clearance = kept[:failed].tolist()
        cert.min_clearance = float(kept[: failed + 1].min(initial=math.inf))
        cert.seconds = time.monotonic() - t0
        return cert

    def certify_curves(self, curves: list[tuple], deadline: float | None = None, *, margin: float | None = None
                       ) -> list[bool]:  # fmt: skip
        """Whether each curve is certified, all in one pass (their pairs share the work): :meth:`prove_curves`."""
        return self.prove_curves(curves, deadline, margin=margin)[0].tolist()

    def prove_curves(self, curves: list[tuple], deadline: float | None = None, *, margin: float | None = None,
                     base: np.ndarray | None = None, joints=None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """Per curve, whether it is certified and the smallest distance measured on it (NaN where it is not), all
        in one pass (their pairs share the work).

        ``curves``: (configurations (n, nq), deviation (nq,)) as :meth:`certify_path` takes them, or
        (configurations, deviation, bend (n - 1, nq)) whose segment i is the parabola
        ``(1 - t) * q_i + t * q_i+1 + (t² - t) * bend[i]`` (a blend proven as the curve it is, no chords).
        With ``joints``, the curves give those joints only (their columns), the others stay at ``base``.
        A curve still unproven at ``deadline`` counts as not certified.
        """
        if not curves:
            return np.zeros(0, dtype=bool), np.zeros(0)
        margin = self.safety_margin if margin is None else float(margin)
        nq = self._model.nq
        columns = np.arange(nq) if joints is None else np.asarray(joints)
        # All curves as one run of segments: the straight step from a curve's end to the next one's start is not proven
        states = [np.reshape(np.asarray(curve[0], dtype=float), (-1, len(columns))) for curve in curves]
        sizes = np.array([len(q) for q in states])
        curve = np.repeat(np.arange(len(curves)), sizes)[:-1]
        curve[np.cumsum(sizes)[:-1] - 1] = -1
        rest = np.zeros(nq) if base is None else np.asarray(base, dtype=float)
        path = np.repeat(rest[None], len(curve) + 1, axis=0)
        path[:, columns] = np.concatenate(states)
        deviation, bend = np.zeros((len(curve), nq)), np.zeros((len(curve), nq))
        proven = curve >= 0
        deviation[np.ix_(proven, columns)] = np.abs(np.array([c[1] for c in curves], dtype=float))[curve[proven]]
        if any(len(c) > 2 for c in curves):
            bend[np.ix_(proven, columns)] = np.concatenate(
                [np.reshape(c[2], (-1, len(columns))) if len(c) > 2 else np.zeros((len(q) - 1, len(columns)))
                 for c, q in zip(curves, states, strict=True)])  # fmt: skip
        _, run = self._certify(path, deviation, curve, margin, deadline, bend)
        certified = ~run.failed_curves(len(curves))
        clearance = np.full(len(curves), math.inf)
        np.minimum.at(clearance, curve[proven], run.clearance[proven])
        return certified, np.where(certified, clearance, math.nan)

    def _certify(
        self, path: np.ndarray, deviation: np.ndarray, curve: np.ndarray, margin: float, deadline: float | None,
        bend: np.ndarray | None = None,
    ) -> tuple[Certificate, CertificationRun]:  # fmt: skip
        """Prove the segments of ``path`` (deviation (segments, nq), ``curve`` and ``bend`` as
        :class:`CertificationRun` takes them; ``bend`` None: straight segments)."""
        bend = np.zeros((max(len(path) - 1, 0), self._model.nq)) if bend is None else bend
        # A bent segment stays within |bend| / 4 of its chord, the reach of the obstacles to consider
        pairs = self._pair_table(self._swept_reach(path, margin, deviation + 0.25 * np.abs(bend)))
        pair_margin = margin + deviation @ pairs.rate.T  # (segments, pairs)
        cert = Certificate(valid=True, margin=margin)
        run = CertificationRun(path, pairs, pair_margin, math.inf if deadline is None else deadline, self._downstream,
                               curve, bend)  # fmt: skip
        while len(run.seg):
            self._check_rows(run, cert)
        return cert, run

    def clearance(self, q: np.ndarray) -> float:
        """Exact smallest distance over all checked pairs at ``q`` (m; <= 0 in collision, inf without pairs).

        Pairs are taken nearest bounding-volume bound first; each is measured on the convex hulls, then on the
        exact geometry only if that is below the smallest exact distance found so far (usually one or two).
        """
        q = np.asarray(q, dtype=float)
        bounds = self._box_bounds(q)
        window = math.inf if bounds is None else float(bounds.min(initial=math.inf)) + CLEARANCE_WINDOW
        best = self._clearance_among(q, None if bounds is None else bounds < window)
        if bounds is not None and best > window:  # farther than the window: the obstacles it left out may be nearer
            best = self._clearance_among(q, bounds < best)
        return best

    def _clearance_among(self, q: np.ndarray, near: np.ndarray | None) -> float:
        """:meth:`clearance` over the self pairs and the reachable obstacles ``near`` selects (None: all)."""
        pairs = self._pair_table(near)
        if not len(pairs.first):
            return math.inf
        centers = self._centers(q[None])
        lower = self._bounds(centers, pairs, np.zeros(len(pairs.first), dtype=int), np.arange(len(pairs.first)))
        pin.forwardKinematics(self._model, self._data, q)
        best, placed = math.inf, set[int]()
        for p in np.argsort(lower):
            if lower[p] >= best:
                break
            if pairs.has_hull[p] and self._distance(pairs, int(p), True, placed) >= best:
                continue
            best = min(best, self._distance(pairs, int(p), False, placed))
        return best

    @property
    def near_path_only(self) -> bool:
        """Whether each certification keeps only the obstacles near what it proves (a large scene: at least
        :data:`NEAR_PATH_MIN_OBSTACLES` reachable obstacles)."""
        return len(self.checker.reachable_obstacles) >= NEAR_PATH_MIN_OBSTACLES

    def prepare(self) -> None:
        """Build what certifying in the checker's current scene needs ahead of the first request: the pair table of
        a small scene, the obstacles' bounding boxes of a large one (both are otherwise built on first use)."""
        if self._obstacle_boxes() is None:
            self._pair_table()

    # ------------------------------------------------------------ internals --
    def _check_rows(self, run: CertificationRun, cert: Certificate) -> None:
        """Evaluate every pending row at the middle of its piece at once; queue the parts still unproven.

        At the middle ``m`` of its piece ``[a, b]`` a row's pair is proven for ``|t - m| <= (d - margin) / rate``;
        what that radius leaves of ``[a, b]`` goes back to the queue as dyadic pieces. Rows at the same
        configuration share its forward kinematics.
        """
        seg, pair = run.seg, run.pair
        configs, config_of, half = round_configs_nb(run.path, run.delta, run.bend, seg, run.a, run.b)
        cert.checks += len(configs)
        n_rows = len(seg)
        margin, bound, rate, need = (np.empty(n_rows) for _ in range(4))
        refine, measured = np.empty(n_rows, dtype=bool), np.empty(n_rows, dtype=bool)
        assess_rows_nb(configs, config_of, seg, pair, half, run.arrays, run.pairs.arrays, self._robot_arrays,
                        self._cover_arrays, self._shape_arrays, run.pairs.primitives, self._cover is not None, margin,
                        bound, rate, need, refine, measured)  # fmt: skip
        exact = self._refine(configs, run.pairs, config_of, pair, refine, measured, margin, bound, need, cert)
        run.seg, run.pair, run.a, run.b = finish_round_nb(
            configs, config_of, seg, pair, run.a, run.b, half, margin, bound, rate, need, refine | measured, exact,
            run.span, time.monotonic() > run.deadline, MIN_INTERVAL, MAX_SPLIT, run.alive, run.curve, run.clearance,
            run.failure, run.witness_config,
        )  # fmt: skip

    def _centers(self, configs: np.ndarray) -> np.ndarray:
        """The geometries' bounding-sphere centres at each configuration (C, geometries, 3), in one numba call."""
        n = len(configs)
        centers = np.empty((n, self._n_robot, 3))
        poses_nb(configs, *self._tree, self._joint, self._local, np.empty((n, self._model.njoints, 3, 3)),
                  np.empty((n, self._model.njoints, 3)), centers)  # fmt: skip
        return centers

    def _warm_row_kernel(self) -> None:
        """Compile (or load) the row kernels for this robot's array types, on no rows (not in a request's budget)."""
        nq, n_geoms, none, no = self._model.nq, self._n_robot, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
        run_arrays = (np.zeros((0, 0)), np.zeros((0, 0)), np.zeros((0, nq)), np.zeros((0, n_geoms, nq)))
        pair_arrays = (none, none, no, none, no, none, np.zeros((0, nq), dtype=bool), np.zeros((0, nq), dtype=bool),
                       np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3)))  # fmt: skip
        assess_rows_nb(np.zeros((1, nq)), none, none, none, np.zeros(0), run_arrays, pair_arrays, self._robot_arrays,
                        self._cover_arrays, self._shape_arrays, kernel_primitives([])[0], self._cover is not None,
                        np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), no, no)  # fmt: skip
        volume_bounds_nb(np.zeros((1, n_geoms, 3)), none, none, *pair_arrays[:3], *pair_arrays[9:], self._radius,
                          np.zeros(0))  # fmt: skip  # clearance() calls it from Python
        proves_too_little(0.0, 0.0)  # so does _refine
        path, rows = np.zeros((2, nq)), np.zeros(0)
        configs, config_of, half = round_configs_nb(path, np.diff(path, axis=0), np.zeros((1, nq)), none, rows, rows)
        finish_round_nb(configs, config_of, none, none, rows, rows, half, rows, rows, rows, rows, no, no, np.zeros(1),
                         False, MIN_INTERVAL, MAX_SPLIT, np.ones(1, dtype=bool), np.zeros(1, dtype=np.int64),
                         np.zeros(1), np.array([1, -1], dtype=np.int64), np.zeros(nq))  # fmt: skip

    def _bounds(self, centers: np.ndarray, pairs: PairTable, config_of: np.ndarray, pair: np.ndarray) -> np.ndarray:
        """Bounding-volume lower bound of each row's pair distance at its configuration."""
        bound = np.empty(len(pair))
        volume_bounds_nb(centers, config_of, pair, pairs.first, pairs.second, pairs.obstacle, pairs.box_center,
                          pairs.box_rot, pairs.box_half, self._radius, bound)  # fmt: skip
        return bound

    def _refine(self, configs, pairs: PairTable, config_of, pair, refine, measured, margin, bound, need,
                cert: Certificate) -> np.ndarray:  # fmt: skip
        """Replace ``bound`` on the ``refine`` rows by a coal distance; returns where it is the exact one.

        A pair with a mesh is first measured on the convex hulls (a lower bound, ~100x cheaper than the
        mesh) unless the row kernel bounded its hulls already (``measured``); the mesh itself where the hull distance
        is within the margin (exact geometry decides) or :func:`proves_too_little` of the piece.
        """
        exact = np.zeros(len(pair), dtype=bool)
        rows = np.flatnonzero(refine)
        if not len(rows):
            return exact
        rows = rows[np.argsort(config_of[rows], kind="stable")]
        current, placed = -1, set[int]()
        for row in rows:
            if config_of[row] != current:
                current, placed = config_of[row], set[int]()
                pin.forwardKinematics(self._model, self._data, configs[current])
            p = int(pair[row])
            if pairs.has_hull[p] and not measured[row]:
                cert.hull_queries += 1
                bound[row] = max(bound[row], self._distance(pairs, p, True, placed))
                slack = bound[row] - margin[row]
                if slack > 0.0 and not proves_too_little(slack, need[row] - margin[row]):
                    continue
            cert.exact_queries += 1
            bound[row] = self._distance(pairs, p, False, placed)
            exact[row] = True
        return exact

    def _distance(self, pairs: PairTable, pair: int, hull: bool, placed: set[int]) -> float:
        """Coal distance of ``pair`` at the last forward kinematics, on the convex hulls if ``hull`` (a lower bound)
        or the exact geometry; the robot's placements are updated once per model (``placed``)."""
        model, data = self._hull_geoms if hull else self._geoms
        if id(model) not in placed:
            pin.updateGeometryPlacements(self._model, self._data, model, data)
            placed.add(id(model))
        if pairs.self_pair[pair] >= 0:
            return pin.computeDistance(model, data, int(pairs.self_pair[pair])).min_distance - DISTANCE_TOLERANCE
        g = int(pairs.first[pair])
        geometry, hull_geometry, placement = pairs.obstacles[pairs.second[pair]]
        request, result = self._query
        result.clear()
        distance = coal.distance(model.geometryObjects[g].geometry, data.oMg[g], hull_geometry if hull else geometry,
                                 placement, request, result)  # fmt: skip
        return distance - DISTANCE_TOLERANCE

    def _robot_geometry(self, shape_of: Callable[[int], coal.CollisionGeometry]):
        """(model, data): the robot's geometry with ``shape_of(g)`` for each geometry and the self pairs."""
        model = self.robot.collision_model.copy()
        for g, obj in enumerate(model.geometryObjects):
            obj.geometry = shape_of(g)
        model.removeAllCollisionPairs()
        for i, j in self._robot_pairs:
            model.addCollisionPair(pin.CollisionPair(i, j))
        return model, pin.GeometryData(model)

    def _pair_table(self, near: np.ndarray | None = None) -> PairTable:
        """The pairs to prove: every pair of the checker in a small scene (or ``near`` None), else the self pairs
        and the pairs of the reachable obstacles ``near`` selects (a bool mask from :meth:`_swept_reach`)."""
        obstacles = self.checker.reachable_obstacles
        if near is None or not self.near_path_only:
            if self._pairs is None or self._pairs_owner is not obstacles:
                self._pairs, self._pairs_owner = self._build_pairs(obstacles), obstacles
            return self._pairs
        if self._near_owner is not obstacles:  # the scene changed: tables of the old obstacles are stale
            self._near_owner, self._near_tables = obstacles, {}
        keep = np.flatnonzero(near)
        key = keep.tobytes()
        table = self._near_tables.pop(key, None)
        if table is None:
            table = self._build_pairs([obstacles[k] for k in keep])
        self._near_tables[key] = table  # most recent last
        while len(self._near_tables) > NEAR_TABLES:
            del self._near_tables[next(iter(self._near_tables))]
        return table

    def _swept_reach(self, path: np.ndarray, margin: float, deviation: np.ndarray) -> np.ndarray | None:
        """In a large scene (None otherwise), which reachable obstacles some pair of ``path`` may come within its
        margin of: on each segment, a moving geometry stays within its bounding radius plus half the segment's
        motion times its levers of the bounding-sphere centre at the segment's middle."""
        boxes = self._obstacle_boxes()
        if boxes is None:
            return None
        mids = 0.5 * (path[:-1] + path[1:]) if len(path) > 1 else path
        travel = 0.5 * np.abs(np.diff(path, axis=0)) @ self._levers.T if len(path) > 1 else np.zeros((1, self._n_robot))
        grown = deviation @ self._levers.T if len(deviation) else 0.0  # deviation: (segments, nq)
        reach = (self._radius + travel + margin + grown)[:, self._moving]  # (segments, geometries)
        centers = self._centers(mids)[:, self._moving]
        box_center, box_rot, box_half = boxes
        lo, hi = (centers - reach[..., None]).min(axis=0), (centers + reach[..., None]).max(axis=0)
        unbounded = ~np.isfinite(box_half).all(axis=1)
        extent = np.einsum("kab,kb->ka", np.abs(box_rot), np.where(unbounded[:, None], 0.0, box_half))  # world AABB
        swept = unbounded | ((box_center - extent <= hi.max(axis=0)) & (box_center + extent >= lo.min(axis=0))).all(1)
        near = np.zeros(len(box_center), dtype=bool)
        near[unbounded] = True  # half-spaces: always
        candidates = np.flatnonzero(swept & ~unbounded)
        subset = (box_center[candidates], box_rot[candidates], box_half[candidates])
        for s in range(len(mids)):  # segments one at a time: (geometries, candidates) arrays stay small
            hit = (box_distances(centers[s], *subset) <= reach[s, :, None]).any(axis=0)
            near[candidates[hit]] = True
        return near

    def _box_bounds(self, q: np.ndarray) -> np.ndarray | None:
        """In a large scene (None otherwise), a lower bound of each reachable obstacle's distance to the robot at
        ``q`` (-inf for a half-space)."""
        boxes = self._obstacle_boxes()
        if boxes is None:
            return None
        centers = self._centers(q[None])
        gaps = box_distances(centers[0, self._moving], *boxes) - self._radius[self._moving, None]
        return np.where(np.isfinite(boxes[2]).all(axis=1), gaps.min(axis=0, initial=math.inf), -math.inf)

    def _obstacle_boxes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(centres, rotations, half extents) of the reachable obstacles' bounding boxes in a large scene, else None."""
        if not self.near_path_only:
            return None
        obstacles = self.checker.reachable_obstacles
        if self._boxes is None or self._boxes[0] is not obstacles:
            boxes = [bounding_box(ob.geometry(), pin.SE3(ob.pose[:3, :3].copy(), ob.pose[:3, 3].copy()))
                     for ob in obstacles]  # fmt: skip
            centers, rotations, halves = (np.array([box[i] for box in boxes], dtype=float) for i in range(3))
            self._boxes = (obstacles, (centers, rotations, halves))
        return self._boxes[1]

    def _build_pairs(self, obstacles: list[Obstacle]) -> PairTable:
        """The table of ``obstacles`` (each against every moving geometry, in the exact checker's order) and the
        self pairs."""
        shapes = []
        for ob in obstacles:
            geometry = ob.geometry()
            shapes.append((geometry, hull_or_self(geometry), pin.SE3(ob.pose[:3, :3].copy(), ob.pose[:3, 3].copy())))
        boxes = [bounding_box(geometry, placement) for geometry, _, placement in shapes]
        box_half = np.array([h for _, _, h, _ in boxes], dtype=float).reshape(-1, 3)
        box_slack = np.array([0.0 if exact else 2.0 * np.linalg.norm(h) for _, _, h, exact in boxes])
        moving = np.flatnonzero(self._moving)
        n_env = len(moving) * len(obstacles)
        self_ends = np.array(self._robot_pairs, dtype=int).reshape(-1, 2)
        first = np.concatenate([np.tile(moving, len(obstacles)), self_ends.min(axis=1)]).astype(int)
        second = np.concatenate([np.repeat(np.arange(len(obstacles)), len(moving)), self_ends.max(axis=1)]).astype(int)
        obstacle = np.arange(len(first)) < n_env
        other = np.where(obstacle, first, second)
        chain_first, chain_other = self._chain[first], self._chain[other] & ~obstacle[:, None]
        moves_first, moves_other = chain_first & ~chain_other, chain_other & ~chain_first
        radius = self._radius
        gap = np.where(obstacle, 2.0 * radius[first], 2.0 * (radius[first] + radius[other]))
        gap[:n_env] += box_slack[second[:n_env]]
        robot_mesh = np.array([isinstance(obj.geometry, coal.BVHModelBase)
                               for obj in self.robot.collision_model.geometryObjects])  # fmt: skip
        obstacle_mesh = np.array([geometry is not hull for geometry, hull, _ in shapes], dtype=bool)
        bounded = np.isfinite(box_half).all(axis=1)
        covered = np.zeros(len(first), dtype=bool)
        if self._cover is not None:
            covered[:n_env] = self._cover.covered[first[:n_env]] & bounded[second[:n_env]]
            covered[n_env:] = self._cover.covered[first[n_env:]] & self._cover.covered[second[n_env:]]
        primitives, exact_primitive = kernel_primitives(obstacles)
        kind = self._shape_arrays[0]
        held = np.concatenate([bounded[second[:n_env]], kind[second[n_env:]] != NO_SHAPE]) & (kind[first] != NO_SHAPE)
        exact = np.concatenate([exact_primitive[second[:n_env]], kind[second[n_env:]] != HULL]) & (kind[first] != HULL)
        return PairTable(
            obstacles=shapes,
            self_pair=np.concatenate([np.full(n_env, -1), np.arange(len(self_ends))]).astype(int),
            has_hull=robot_mesh[first] | np.concatenate([obstacle_mesh[second[:n_env]], robot_mesh[second[n_env:]]]),
            first=first,
            second=second,
            obstacle=obstacle,
            other=other,
            moves_first=moves_first,
            moves_other=moves_other,
            rate=moves_first * self._levers[first] + moves_other * self._levers[other],
            gap=gap,
            box_center=np.array([c for c, _, _, _ in boxes], dtype=float).reshape(-1, 3),
            box_rot=np.array([r for _, r, _, _ in boxes], dtype=float).reshape(-1, 3, 3),
            box_half=box_half,
            covered=covered,
            measure=np.where(held, np.where(exact, MEASURE_EXACT, MEASURE_BOUND), MEASURE_NONE).astype(np.int64),
            primitives=primitives,
        )
