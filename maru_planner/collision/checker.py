"""CollisionChecker: robot self-collision (SRDF-filtered) + robot-vs-scene, on Pinocchio + coal.

One Pinocchio ``Data`` and one ``GeometryData`` are built per scene and reused
for every check. Whenever the scene changes (``set_scene`` or any edit that
bumps ``scene.version``) everything scene-related is rebuilt from scratch, so a
removed obstacle never leaves a stale pair behind. The build is linear in the
number of obstacles and bounded by ``build_budget`` (InvalidScene when it runs out):

- obstacles the robot can never reach are dropped (:mod:`maru_planner.collision.broadphase`);
- up to ``PAIR_LIST_LIMIT`` reachable obstacles join the robot's geometry model as
  (moving link, obstacle) pairs, ahead of the self-collision pairs: in planning they
  are the ones that usually fail, and ``stop_at_first_collision`` then returns early;
- more than that go in a coal AABB tree (``SceneTree``), one tree-vs-tree query per check.

Validity checks (``is_valid``, ``are_valid``, ``first_invalid``,
``any_invalid``) go through a coal broad phase, which skips the narrow phase
of every pair whose bounding boxes do not overlap -- most pairs, most of the
time (bench/collision.py: 3-6x faster than ``pinocchio.computeCollisions``
over the same pairs). ``broadphase="auto"`` picks the naive manager (AABB test
per pair) for primitive-only robots and a dynamic AABB tree when the robot
has meshes. With ``padding`` > 0 the broad phase stays: Pinocchio's manager
inflates each box by half the largest security margin of its pairs.
"""

from __future__ import annotations

import functools
from itertools import combinations

import coal
import numpy as np
import pinocchio as pin

from maru_planner.collision.broadphase import SceneTree, robot_reach
from maru_planner.collision.kernels.bisection import bisection_order
from maru_planner.robot.model import RobotModel
from maru_planner.scene import BuildClock, Obstacle, Scene

PAIR_LIST_LIMIT = 64  # reachable obstacles kept as pairs; beyond, the tree's per-check cost is lower


BROADPHASES = {
    "none": None,
    "naive": pin.BroadPhaseManager_NaiveCollisionManager,
    "aabb_tree": pin.BroadPhaseManager_DynamicAABBTreeCollisionManager,
}


def self_collision_pairs(robot: RobotModel) -> list[tuple[int, int]]:
    """Geometry index pairs to check for self-collision.

    Excluded: geometries on the same rigid body, link pairs disabled in the
    SRDF and -- for robots loaded without SRDF collision info -- parent/child bodies.
    """
    model, geoms = robot.model, robot.collision_model.geometryObjects
    disabled = robot.srdf.disabled_pairs
    skip_adjacent = getattr(robot, "skip_adjacent_pairs", not disabled)
    links = [model.frames[g.parentFrame].name for g in geoms]
    pairs = []
    for i, j in combinations(range(len(geoms)), 2):
        ji, jj = geoms[i].parentJoint, geoms[j].parentJoint
        if ji == jj or frozenset((links[i], links[j])) in disabled:
            continue
        if skip_adjacent and (model.parents[ji] == jj or model.parents[jj] == ji):
            continue
        pairs.append((i, j))
    return pairs


class CollisionChecker:
    """Validity of full robot configurations against self-collision and a scene."""

    def __init__(
        self,
        robot: RobotModel,
        scene: Scene | None = None,
        *,
        padding: float = 0.0,
        broadphase: str = "auto",
        build_budget: float | None = None,
        pair_list_limit: int = PAIR_LIST_LIMIT,
    ):
        """``padding`` (m) is added to every pair's security margin: closer than that counts as collision.

        ``broadphase``: "auto", "naive", "aabb_tree" or "none" (pair loop only), for the pair list.
        ``build_budget``: seconds a scene build may take (None: no limit); InvalidScene when exceeded.
        ``pair_list_limit``: most reachable obstacles checked as a pair list; more go in an AABB tree.
        """
        if broadphase != "auto" and broadphase not in BROADPHASES:
            raise ValueError(f"broadphase must be 'auto' or one of {sorted(BROADPHASES)}, got {broadphase!r}")
        self.robot = robot
        self.padding = float(padding)
        if broadphase == "auto":
            has_mesh = any(isinstance(g.geometry, coal.BVHModelBase) for g in robot.collision_model.geometryObjects)
            broadphase = "aabb_tree" if has_mesh else "naive"
        self.broadphase = broadphase
        self.check_count = 0
        self.build_budget = build_budget
        self.pair_list_limit = int(pair_list_limit)
        self.reach = robot_reach(robot)
        self.scene_tree: SceneTree | None = None  # set when the reachable obstacles exceed PAIR_LIST_LIMIT
        self._self_pairs = self_collision_pairs(robot)
        self._model = robot.model
        self._data = robot.model.createData()
        self._scene_version = -1
        self.set_scene(scene if scene is not None else Scene())

    # -------------------------------------------------------------- scene --
    @property
    def scene(self) -> Scene:
        return self._scene

    def set_scene(self, scene: Scene) -> None:
        """Use ``scene`` (later edits to it are picked up automatically)."""
        self._scene = scene
        self._build()

    def _build(self) -> None:
        clock = BuildClock(self.build_budget, len(self._scene.obstacles))
        self._reachable = self._scene.obstacles_within(self.reach + self.padding, clock)
        listed = self._reachable if len(self._reachable) <= self.pair_list_limit else []
        tree = SceneTree(self.robot, self._reachable, self.padding, clock) if not listed and self._reachable else None
        self.scene_tree = tree
        self._geom_model, self._pair_names = self._pair_model(listed)
        self._full_model = None if tree is not None else self._geom_model
        self._geom_data = pin.GeometryData(self._geom_model)
        for request in self._geom_data.collisionRequests:
            request.security_margin = self.padding
            request.enable_contact = False
        self._scene_version = self._scene.version
        manager = BROADPHASES[self.broadphase]
        has_pairs = bool(self._pair_names)
        self._manager = manager(self._model, self._geom_model, self._geom_data) if manager and has_pairs else None

    def _pair_model(self, listed: list[Obstacle]) -> tuple[pin.GeometryModel, list[tuple[str, str]]]:
        """Robot geometry + ``listed`` obstacles, with (moving link, obstacle) pairs first, then self pairs."""
        geom_model = self.robot.collision_model.copy()
        n_robot = geom_model.ngeoms
        names = [self._model.frames[g.parentFrame].name for g in geom_model.geometryObjects]
        for obstacle in listed:
            placement = pin.SE3(obstacle.pose[:3, :3].copy(), obstacle.pose[:3, 3].copy())
            obj = pin.GeometryObject(f"scene/{obstacle.name}", 0, 0, placement, obstacle.geometry())
            geom_model.addGeometryObject(obj)
            names.append(obstacle.name)
        moving = [i for i in range(n_robot) if geom_model.geometryObjects[i].parentJoint != 0]
        pairs = [(i, k) for k in range(n_robot, geom_model.ngeoms) for i in moving] + self._self_pairs
        geom_model.removeAllCollisionPairs()
        for i, j in pairs:
            geom_model.addCollisionPair(pin.CollisionPair(i, j))
        return geom_model, [(names[i], names[j]) for i, j in pairs]

    def _collides(self, q: np.ndarray) -> bool:
        if self._manager is not None:
            hit = pin.computeCollisions(self._model, self._data, self._manager, q, True)
        else:
            hit = pin.computeCollisions(self._model, self._data, self._geom_model, self._geom_data, q, True)
        if hit or self.scene_tree is None:
            return hit
        return self.scene_tree.collides(self._data)  # the pair list's call left the kinematics in _data

    def _sync(self) -> None:
        if self._scene.version != self._scene_version:
            self._build()

    @property
    def n_pairs(self) -> int:
        """Number of geometry pairs that can be checked per configuration (the tree skips most)."""
        self._sync()
        return len(self._pair_names) + (self.scene_tree.n_pairs if self.scene_tree is not None else 0)

    @property
    def checked_pairs(self) -> list[tuple[str, str]]:
        """(link or obstacle, link or obstacle) names of every pair that can be checked."""
        self._sync()
        return self._pair_names + (self.scene_tree.pair_names() if self.scene_tree is not None else [])

    @property
    def geometry_model(self) -> pin.GeometryModel:
        """Robot + every reachable obstacle, its ``collisionPairs`` the checked pairs (current scene; do not
        modify). With a scene tree this pair list is built on first use (obstacles x moving links; each object
        Pinocchio adds resizes its pair matrix: thousands of obstacles take minutes)."""
        self._sync()
        if self._full_model is None:
            self._full_model = self._pair_model(self._reachable)[0]
        return self._full_model

    @property
    def reachable_obstacles(self) -> list[Obstacle]:
        """The scene's obstacles the robot can reach, the only ones checked (a new list after each rebuild)."""
        self._sync()
        return self._reachable

    # ------------------------------------------------------------- checks --
    def is_valid(self, q: np.ndarray) -> bool:
        """True if ``q`` (full configuration) is free of self- and scene collision."""
        self._sync()
        self.check_count += 1
        return not self._collides(q)

    def are_valid(self, Q: np.ndarray) -> np.ndarray:
        """Validity of each row of ``Q`` (n, nq)."""
        self._sync()
        Q = np.asarray(Q, dtype=float)
        out = np.empty(len(Q), dtype=bool)
        collides = self._collides
        for k, q in enumerate(Q):
            out[k] = not collides(q)
        self.check_count += len(Q)
        return out

    def first_invalid(self, Q: np.ndarray) -> int:
        """Index of the first invalid row of ``Q`` (-1 if all valid); stops at the first hit."""
        self._sync()
        collides = self._collides
        for k, q in enumerate(np.asarray(Q, dtype=float)):
            self.check_count += 1
            if collides(q):
                return k
        return -1

    def any_invalid(self, Q: np.ndarray) -> bool:
        """True if some row of ``Q`` is invalid; checks in bisection order (ends, middle, quarters, ...).

        For a discretised edge the middle is the likeliest to collide when the
        ends are known valid, so invalid edges are rejected after few checks.
        """
        self._sync()
        Q = np.asarray(Q, dtype=float)
        collides = self._collides
        for k in bisection_order(len(Q)):
            self.check_count += 1
            if collides(Q[k]):
                return True
        return False

    def colliding_pairs(self, q: np.ndarray) -> list[tuple[str, str]]:
        """Names (link or obstacle) of every colliding pair at ``q``; empty if valid."""
        self._sync()
        self.check_count += 1
        pin.computeCollisions(self._model, self._data, self._geom_model, self._geom_data, q, False)
        hits = [self._pair_names[k] for k, r in enumerate(self._geom_data.collisionResults) if r.isCollision()]
        if self.scene_tree is not None:
            hits = self.scene_tree.colliding_pairs(self._data) + hits
        return list(dict.fromkeys(hits))

    def clearance(self, q: np.ndarray) -> float:
        """Minimum distance over all checked pairs (m); <= 0 when in collision."""
        return self.closest_pair(q)[1] - self.padding

    def closest_pair(self, q: np.ndarray) -> tuple[tuple[str, str], float]:
        """(names, distance) of the closest pair at ``q``; (("", ""), inf) without pairs."""
        self._sync()
        self.check_count += 1
        pin.computeDistances(self._model, self._data, self._geom_model, self._geom_data, q)
        best, best_pair = np.inf, ("", "")
        if self._pair_names:
            d = [r.min_distance for r in self._geom_data.distanceResults]
            k = int(np.argmin(d))
            best, best_pair = float(d[k]), self._pair_names[k]
        if self.scene_tree is not None:
            pair, distance = self.scene_tree.nearest(self._data)
            if distance < best:
                best, best_pair = distance, pair
        return best_pair, best

    def reset_count(self) -> None:
        self.check_count = 0


def convex_hull(mesh: coal.BVHModelBase) -> coal.ConvexBase:
    """The convex hull of a mesh's vertices: contains the mesh, so its distances are lower bounds."""
    points = coal.StdVec_Vec3s()
    for vertex in np.asarray(mesh.vertices(), dtype=float):
        points.append(vertex)
    return coal.Convex.convexHull(points, False, "Qt")


def hull_or_self(shape: coal.CollisionGeometry) -> coal.CollisionGeometry:
    """A cheaper lower bound for distances to ``shape``: its convex hull if it is a mesh, else the shape itself."""
    return convex_hull(shape) if isinstance(shape, coal.BVHModelBase) else shape


#: :func:`hull_or_self` of a robot's geometry, kept: the certifier and every sphere checker of the robot (padded
#: twins included) share one hull per mesh instead of each running Qhull again.
robot_hull = functools.lru_cache(maxsize=64)(hull_or_self)
