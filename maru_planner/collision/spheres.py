"""A fast, batched collision checker on a sphere approximation of the robot (VAMP-style).

The robot's collision geometry is covered by spheres (:mod:`maru_planner.collision.sphere_model`:
every surface triangle of every link lies inside a sphere, so the spheres over-approximate the
links); forward kinematics and all tests for a whole batch of configurations run in one numba call
(:mod:`maru_planner.collision.kernels.sphere_scan`), with a pure-numpy path that gives the same answers.
Each obstacle is tested as the kernel primitive its shape's table entry gives (``maru_planner/shapes.py``):
boxes, spheres and cylinders exactly; a mesh by its oriented bounding box, whose touches the exact
model decides.

Same protocol as the exact :class:`~maru_planner.collision.checker.CollisionChecker`: ``is_valid``,
``are_valid``, ``first_invalid``, ``colliding_pairs``, ``clearance``, ``check_count``,
``reset_count``, ``set_scene``, all on full robot configurations (length ``nq``).

"Verified on the exact model" (see ``docs/fast_collision.md``): planning runs on the spheres; the
planner's final path is re-checked with the exact checker by :func:`verify_path` at a finer
resolution; a path that fails is re-planned finer and never returned as valid. ``MotionPlanner.plan``
does this for any planner on a sphere checker (``PlannerConfig.collision_model="spheres"``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import coal
import numpy as np

from maru_planner.collision.broadphase import robot_reach
from maru_planner.collision.checker import hull_or_self, robot_hull, self_collision_pairs
from maru_planner.collision.kernels.fk import frame_placements_nb, joint_poses_nb, sphere_centers_nb
from maru_planner.collision.kernels.grid import NO_GRID, build_grid
from maru_planner.collision.kernels.packing import pack_robot, pack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, COLLIDING, VALID
from maru_planner.collision.kernels.sphere_scan import scan_nb, sphere_obstacle_distances_nb
from maru_planner.collision.kinematic_tree import KinematicTree, batch_joint_poses
from maru_planner.collision.shape_records import robot_shape_records
from maru_planner.collision.sphere_model import SphereFitOptions, SphereModel, load_or_fit
from maru_planner.scene import BuildClock, Obstacle, Scene
from maru_planner.scene.shapes import KERNEL_KINDS, KernelPrimitive

DEFAULT_PADDING = 0.0  # m added to every robot sphere; the spheres already cover the links (module doc)
GRID_MIN_OBSTACLES = 32  # reachable obstacles from which the kernels look them up in a grid
GRID_MAX_CELLS = 512  # an obstacle overlapping more grid cells is tested by every query instead


@dataclass(frozen=True)
class ScenePrimitives:
    """A scene's obstacles as arrays per kernel kind; ``names`` in kernel order (boxes, spheres, cylinders).

    Each obstacle's kernel primitive comes from its shape's table entry (:mod:`maru_planner.shapes`);
    ``exact[k]`` is False where the primitive only bounds the obstacle (a mesh's box): touching it
    never decides a collision by itself.
    """

    box_center: np.ndarray  # (nb, 3)
    box_rot: np.ndarray  # (nb, 3, 3) world-from-box
    box_half: np.ndarray  # (nb, 3)
    sphere_center: np.ndarray  # (ns, 3)
    sphere_radius: np.ndarray  # (ns,)
    cyl_center: np.ndarray  # (nc, 3)
    cyl_axis: np.ndarray  # (nc, 3) unit
    cyl_half: np.ndarray  # (nc,)
    cyl_radius: np.ndarray  # (nc,)
    exact: np.ndarray  # (n,) bool, kernel order
    names: tuple[str, ...]
    obstacles: tuple[Obstacle, ...] = ()  # in the same order as ``names``

    def as_tuple(self) -> tuple:
        return (
            self.box_center, self.box_rot, self.box_half, self.sphere_center, self.sphere_radius,
            self.cyl_center, self.cyl_axis, self.cyl_half, self.cyl_radius, self.exact,
        )  # fmt: skip

    @classmethod
    def from_scene(cls, scene: Scene | None, reach: float = np.inf, clock: BuildClock | None = None) -> ScenePrimitives:
        """Convert a :class:`~maru_planner.scene.Scene` (``None`` = empty), keeping the obstacles whose
        bounding sphere comes within ``reach`` of the root origin."""
        obstacles = scene.obstacles_within(reach, clock) if scene is not None else []
        return cls.from_obstacles(obstacles, clock)

    @classmethod
    def from_obstacles(cls, obstacles: list[Obstacle], clock: BuildClock | None = None) -> ScenePrimitives:
        """Convert ``obstacles`` (``clock`` ticks once per obstacle)."""
        clock = clock or BuildClock(None, len(obstacles))
        by_kind: dict[str, list[tuple[Obstacle, KernelPrimitive]]] = {kind: [] for kind in KERNEL_KINDS}
        for k, obstacle in enumerate(obstacles):
            clock.tick(k, "converting obstacles to primitives")
            primitive = obstacle.kernel_primitive()
            by_kind[primitive.kind].append((obstacle, primitive))
        boxes, spheres, cylinders = (by_kind[kind] for kind in KERNEL_KINDS)
        ordered = boxes + spheres + cylinders
        return cls(
            box_center=_stack([p.center for _, p in boxes], (3,)),
            box_rot=_stack([p.rotation for _, p in boxes], (3, 3)),
            box_half=_stack([p.half_extents for _, p in boxes], (3,)),
            sphere_center=_stack([p.center for _, p in spheres], (3,)),
            sphere_radius=_stack([p.half_extents[0] for _, p in spheres], ()),
            cyl_center=_stack([p.center for _, p in cylinders], (3,)),
            cyl_axis=_stack([p.rotation[:, 2] for _, p in cylinders], (3,)),
            cyl_half=_stack([p.half_extents[2] for _, p in cylinders], ()),
            cyl_radius=_stack([p.half_extents[0] for _, p in cylinders], ()),
            exact=np.array([p.exact for _, p in ordered], dtype=bool),
            names=tuple(o.name for o, _ in ordered),
            obstacles=tuple(o for o, _ in ordered),
        )

    def boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned boxes (lo, hi), each (n, 3), of the primitives in kernel order."""
        box_half = np.einsum("kab,kb->ka", np.abs(self.box_rot), self.box_half)
        radial = np.sqrt(np.clip(1.0 - self.cyl_axis**2, 0.0, None))
        cyl_half = np.abs(self.cyl_axis) * self.cyl_half[:, None] + radial * self.cyl_radius[:, None]
        centers = np.concatenate([self.box_center, self.sphere_center, self.cyl_center])
        halves = np.concatenate([box_half, np.repeat(self.sphere_radius[:, None], 3, axis=1), cyl_half])
        return centers - halves, centers + halves


def _stack(values: list, shape: tuple[int, ...]) -> np.ndarray:
    return np.array(values, dtype=float).reshape(-1, *shape)


def self_collision_groups(robot) -> np.ndarray:
    """Geometry pairs tested against each other: exactly the exact checker's SRDF-filtered pairs."""
    return np.array(self_collision_pairs(robot), dtype=np.int64).reshape(-1, 2)


class SphereCollisionChecker:
    """Batched collision checks of a robot, as spheres, against a scene and itself.

    ``confirm=True`` (default): a state's answer is the exact model's — spheres only settle the clear
    cases (outer spheres free: valid; inner balls touching: colliding) and every near contact in
    between is decided by coal on the touching (link, obstacle) or (link, link) pairs alone.
    ``confirm=False``: the pure sphere model, conservative (never calls a colliding state valid,
    may call a state within ~``max_protrusion`` of contact colliding).
    """

    def __init__(
        self,
        robot,
        scene=None,
        *,
        padding: float = DEFAULT_PADDING,
        confirm: bool = True,
        fit_options: SphereFitOptions | None = None,
        spheres: SphereModel | None = None,
        use_numba: bool = True,
        build_budget: float | None = None,
        grid_min_obstacles: int = GRID_MIN_OBSTACLES,
    ):
        """``build_budget``: seconds a scene build may take (None: no limit; InvalidScene when exceeded).
        ``grid_min_obstacles``: reachable obstacles from which a grid broad phase is built (numba path)."""
        self.robot = robot
        self.tree = KinematicTree.from_pinocchio(robot.model)
        fit_options = fit_options or getattr(robot, "sphere_options", None)  # None: the defaults
        self.spheres = spheres or load_or_fit(robot.model, robot.collision_model, fit_options)
        self.self_pairs = self_collision_groups(robot)
        self.padding = float(padding)
        self.confirm = bool(confirm)
        self.use_numba = bool(use_numba)
        self.build_budget = build_budget
        self.grid_min_obstacles = int(grid_min_obstacles)
        self.reach = robot_reach(robot)
        self.check_count = 0
        self.exact_pair_checks = 0  # coal calls made to settle near contacts
        self.scene = None
        sm = self.spheres
        self._robot_args = (
            self.tree.parent, self.tree.kind, self.tree.axis, self.tree.placement_rot, self.tree.placement_pos,
            self.tree.idx_q, sm.joint, sm.center, sm.radius, sm.inner, sm.group_start, sm.group_joint,
            sm.group_center, sm.group_radius, self.self_pairs, self.padding,
        )  # fmt: skip
        clusters = (sm.cluster_start, sm.cluster_joint, sm.cluster_center, sm.cluster_radius, sm.group_clusters)
        self._packed_robot = pack_robot(*self._robot_args, *clusters) if self.use_numba else None
        self._robot_geoms = list(robot.collision_model.geometryObjects)
        self._exact_shapes = [obj.geometry for obj in self._robot_geoms]  # the exact checker's own shapes
        # each geometry's joint and placement in it, and its world placement at the last _exact_hit's state
        self._geom_frames = (
            np.array([obj.parentJoint for obj in self._robot_geoms], dtype=np.int64),
            np.array([obj.placement.rotation for obj in self._robot_geoms]).reshape(-1, 3, 3),
            np.array([obj.placement.translation for obj in self._robot_geoms]).reshape(-1, 3),
        )
        n_geoms = len(self._robot_geoms)
        self._geom_rot, self._geom_pos = np.empty((n_geoms, 3, 3)), np.empty((n_geoms, 3))
        self._rot = np.empty((self.tree.njoints, 3, 3))
        self._pos = np.empty((self.tree.njoints, 3))
        self._sphere_pairs = self._expand_pairs()
        # the robot's boxes, spheres and cylinders, on which the search kernels settle near contacts by GJK; not its
        # meshes' hulls: on MotionBenchMaker's Panda they cleared 15 % of the states coal is asked about, and cost more
        self._shapes = robot_shape_records(self._robot_geoms, {})
        self.set_scene(scene)
        if self.use_numba:  # compile (or load) the placement kernel now, not in a request's first exact check
            self._place_geometries(np.asarray(robot.neutral(), dtype=float))

    # ------------------------------------------------------------ protocol --
    def set_scene(self, scene) -> None:
        """Use ``scene``; later edits to it (``scene.version`` bumps) are picked up automatically."""
        self.scene = scene
        clock = BuildClock(self.build_budget, len(scene.obstacles) if scene is not None else 0)
        self.primitives = ScenePrimitives.from_scene(scene, self.reach + self.padding, clock)
        self._scene_args = self.primitives.as_tuple()
        self._packed_scene = pack_scene(*self._scene_args) if self.use_numba else None
        self._grid = self._build_grid()
        self._mark = np.zeros((2, len(self.primitives.names) + 1), dtype=np.int64)
        self._scene_version = getattr(scene, "version", None)
        self._amb = np.zeros(
            (self.spheres.n_groups * max(1, len(self.primitives.names)) + len(self.self_pairs), 3), dtype=np.int64
        )
        self._request: coal.CollisionRequest | None = None

    @property
    def uses_grid(self) -> bool:
        """Whether the kernels look obstacles up in a grid (large scenes) rather than test them all."""
        return bool(self._grid[0][0] > 0)

    def kernel_inputs(self) -> tuple:
        """The current scene's arrays for compiled callers, in ``scan_nb``'s order after ``Q, start``: packed
        robot (ints, floats), packed scene, grid (ints, floats) and the work arrays ``amb``, ``mark`` (numba only);
        then the records of the robot's primitive shapes (``shape_records.robot_shape_records``), on which the
        search kernels settle near contacts before asking coal."""
        self._sync()
        ri, rf, scene = self._packed()
        return ri, rf, scene, *self._grid, self._amb, self._mark, self._shapes

    def _packed(self) -> tuple[Any, Any, Any]:
        """The numba kernels' packed robot (ints, floats) and packed scene."""
        if self._packed_robot is None or self._packed_scene is None:
            raise RuntimeError("packed arrays exist only with use_numba")
        return (*self._packed_robot, self._packed_scene)

    def _build_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Grid broad phase over the reachable obstacles, cells about one robot sphere cluster's bound across."""
        if not self.use_numba or len(self.primitives.names) < self.grid_min_obstacles:
            return NO_GRID
        lo, hi = self.primitives.boxes()
        moving = self.spheres.cluster_joint != 0
        cell = float(np.median(self.spheres.cluster_radius[moving])) if moving.any() else 0.1
        cell = max(cell, float((hi.max(axis=0) - lo.min(axis=0)).max()) / 64.0, 1e-3)
        return build_grid(lo - self.padding, hi + self.padding, cell, GRID_MAX_CELLS)

    def reset_count(self) -> None:
        self.check_count = 0
        self.exact_pair_checks = 0

    def is_valid(self, q) -> bool:
        return self.first_invalid(np.asarray(q, dtype=float).reshape(1, -1)) < 0

    def first_invalid(self, Q) -> int:
        """Index of the first colliding row (-1 if none); rows after it are not checked."""
        Q = self._batch(Q)
        start = 0
        while True:
            row, status, n_amb = self._scan(Q, start)
            if row < 0:
                self.check_count += len(Q) - start
                return -1
            self.check_count += row + 1 - start
            if status == COLLIDING or self._exact_hit(Q[row], self._amb[:n_amb]):
                return row
            start = row + 1

    def are_valid(self, Q) -> np.ndarray:
        Q = self._batch(Q)
        out = np.ones(len(Q), dtype=bool)
        start = 0
        while start < len(Q):
            row, status, n_amb = self._scan(Q, start)
            if row < 0:
                break
            out[row] = not (status == COLLIDING or self._exact_hit(Q[row], self._amb[:n_amb]))
            start = row + 1
        self.check_count += len(Q)
        return out

    def colliding_pairs(self, q) -> list[tuple[str, str]]:
        """(link, obstacle) and (link, link) pairs in collision, links named by their frame."""
        q = self._batch(q)[0]
        self.check_count += 1
        env, self_gap = self._pair_gaps(q)
        links, names = self.spheres.group_links, self.primitives.names
        out = []
        for g, k in zip(*np.nonzero(env < 0.0)):
            if not self.confirm or self._exact_hit(q, np.array([[0, g, k]])):
                out.append((links[g], names[k]))
        for p in np.flatnonzero(self_gap < 0.0):
            a, b = self.self_pairs[p]
            if not self.confirm or self._exact_hit(q, np.array([[1, a, b]])):
                out.append((links[a], links[b]))
        return list(dict.fromkeys(out))

    def clearance(self, q) -> float:
        """Smallest gap between outer spheres and obstacles or self-collision pairs, minus ``padding`` (m).

        A lower bound of the exact clearance: the outer spheres contain the links.
        """
        env, self_gap = self._pair_gaps(self._batch(q)[0])
        self.check_count += 1
        return float(min([np.inf, *env.ravel().tolist(), *self_gap.tolist()]))

    # ------------------------------------------------------------ helpers --
    def sphere_centers(self, q) -> np.ndarray:
        """World centres (n_spheres, 3) of the robot spheres at configuration ``q``."""
        rot, pos = self._joint_poses(np.asarray(q, dtype=float))
        out = np.empty((self.spheres.n_spheres, 3))
        sphere_centers_nb(rot, pos, self.spheres.joint, self.spheres.center, out)
        return out

    def _joint_poses(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.use_numba:
            joint_poses_nb(q, *self._robot_args[:6], self._rot, self._pos)
            return self._rot, self._pos
        rot, pos = batch_joint_poses(self.tree, q[None])
        return rot[0], pos[0]

    def _sync(self) -> None:
        if self.scene is not None and getattr(self.scene, "version", None) != self._scene_version:
            self.set_scene(self.scene)

    def _batch(self, Q) -> np.ndarray:
        self._sync()
        Q = np.ascontiguousarray(np.atleast_2d(np.asarray(Q, dtype=float)))
        if Q.ndim != 2 or Q.shape[1] != self.tree.nq:
            raise ValueError(f"configurations must have {self.tree.nq} values (robot nq), got shape {Q.shape}")
        return Q

    def _scan(self, Q: np.ndarray, start: int) -> tuple[int, int, int]:
        """First row >= start that is not clearly valid: (row, status, number of ambiguous pairs)."""
        if self.use_numba:
            ri, rf, scene = self._packed()
            row, status, n_amb = scan_nb(Q, start, ri, rf, scene, *self._grid, self._amb, self._mark, self.confirm)
            return int(row), int(status), int(n_amb)
        for row in range(start, len(Q)):
            status, pairs = self._classify_np(Q[row])
            if status != VALID:
                self._amb[: len(pairs)] = pairs
                return row, status if self.confirm else COLLIDING, len(pairs)
        return -1, VALID, 0

    def _exact_hit(self, q: np.ndarray, pairs: np.ndarray) -> bool:
        """Whether coal finds any of the (kind, a, b) pairs in collision (within ``padding``) at ``q``.

        A pair with a mesh is first tested on the convex hulls: clear there (the usual case, the spheres stick
        out of the hull by up to ``max_protrusion``), it is clear on the mesh, ~10x cheaper.
        """
        if self._request is None:
            self._request = coal.CollisionRequest()
            self._request.security_margin = self.padding
            self._request.enable_contact = False
            self._result = coal.CollisionResult()  # reused, cleared before each query (making one costs ~1 µs)
            self._obstacle_shapes: dict[int, tuple] = {}  # by kernel index, made on first use (most never are)
        self._place_geometries(q)
        placed: dict[int, tuple] = {}
        for kind, a, b in pairs:
            self.exact_pair_checks += 1
            shape_a, hull_a, tf_a = self._link_shape(a, placed)
            shape_b, hull_b, tf_b = self._obstacle_shape(b) if kind == 0 else self._link_shape(b, placed)
            hulls = hull_a is not shape_a or hull_b is not shape_b
            self._result.clear()
            if hulls and not coal.collide(hull_a, tf_a, hull_b, tf_b, self._request, self._result):
                continue
            self._result.clear()
            if coal.collide(shape_a, tf_a, shape_b, tf_b, self._request, self._result) > 0:
                return True
        return False

    def _place_geometries(self, q: np.ndarray) -> None:
        """Every robot geometry's world placement at ``q`` (``_geom_rot``, ``_geom_pos``), in one numba call."""
        rot, pos = self._joint_poses(q)
        joint, local_rot, local_pos = self._geom_frames
        if self.use_numba:
            frame_placements_nb(rot, pos, joint, local_rot, local_pos, self._geom_rot, self._geom_pos)
        else:
            self._geom_rot[:] = rot[joint] @ local_rot
            self._geom_pos[:] = np.einsum("gab,gb->ga", rot[joint], local_pos) + pos[joint]

    def _obstacle_shape(self, k: int) -> tuple:
        """(shape, its convex hull or itself, coal placement) of obstacle ``k`` (kernel order), made once per scene."""
        shape = self._obstacle_shapes.get(k)
        if shape is None:
            ob = self.primitives.obstacles[k]
            shape = self._obstacle_shapes[k] = _with_hull(ob.geometry(), _coal_tf(ob.pose[:3, :3], ob.pose[:3, 3]))
        return shape

    def _link_shape(self, g: int, placed: dict[int, tuple]) -> tuple:
        """(shape, its convex hull or itself, coal placement) of robot geometry ``g`` at the last placements."""
        if g not in placed:
            shape = self._exact_shapes[g]
            placed[g] = (shape, robot_hull(shape), coal.Transform3s(self._geom_rot[g], self._geom_pos[g]))
        return placed[g]

    def _expand_pairs(self) -> np.ndarray:
        """Sphere index pairs (m, 3): sphere a, sphere b, index of the group pair."""
        rows = []
        st = self.spheres.group_start
        for p, (a, b) in enumerate(self.self_pairs):
            sa, sb = np.arange(st[a], st[a + 1]), np.arange(st[b], st[b + 1])
            grid = np.stack(np.meshgrid(sa, sb, indexing="ij"), axis=-1).reshape(-1, 2)
            rows.append(np.c_[grid, np.full(len(grid), p)])
        return np.concatenate(rows).astype(np.int64) if rows else np.zeros((0, 3), dtype=np.int64)

    def _world_centers_np(self, q: np.ndarray) -> np.ndarray:
        rot, pos = batch_joint_poses(self.tree, q[None])
        j = self.spheres.joint
        return np.einsum("sab,sb->sa", rot[0, j], self.spheres.center) + pos[0, j]

    def _obstacle_distances_np(self, world: np.ndarray) -> np.ndarray:
        """Signed distances (n_points, n_obstacles) from points to every obstacle, numpy only."""
        p = self.primitives
        parts = []
        if len(p.box_center):
            local = np.einsum("kab,ska->skb", p.box_rot, world[:, None, :] - p.box_center)
            excess = np.abs(local) - p.box_half
            outside = np.linalg.norm(np.maximum(excess, 0.0), axis=-1)
            parts.append(np.where(outside > 0.0, outside, excess.max(axis=-1)))
        if len(p.sphere_center):
            parts.append(np.linalg.norm(world[:, None, :] - p.sphere_center, axis=-1) - p.sphere_radius)
        if len(p.cyl_center):
            d = world[:, None, :] - p.cyl_center
            t = np.einsum("ska,ka->sk", d, p.cyl_axis)
            radial = np.linalg.norm(d - t[..., None] * p.cyl_axis, axis=-1)
            ez, er = np.abs(t) - p.cyl_half, radial - p.cyl_radius
            outside = np.hypot(np.maximum(ez, 0.0), np.maximum(er, 0.0))
            parts.append(np.where((ez > 0.0) | (er > 0.0), outside, np.maximum(ez, er)))
        if not parts:
            return np.zeros((len(world), 0))
        return np.concatenate(parts, axis=-1)

    def _sphere_gaps_np(self, q: np.ndarray):
        """Per sphere x obstacle and per sphere pair: (outer gaps, inner gaps) minus padding, numpy only."""
        world = self._world_centers_np(q)
        sm, pad = self.spheres, self.padding
        dist = self._obstacle_distances_np(world)
        dist[sm.joint == 0] = np.inf  # fixed to the world: never tested against the scene
        env_outer = dist - sm.radius[:, None] - pad
        env_inner = np.where(self.primitives.exact, dist, np.inf) - sm.inner[:, None] - pad
        a, b = self._sphere_pairs[:, 0], self._sphere_pairs[:, 1]
        d = np.linalg.norm(world[a] - world[b], axis=-1)
        return env_outer, env_inner, d - sm.radius[a] - sm.radius[b] - pad, d - sm.inner[a] - sm.inner[b] - pad

    def _classify_np(self, q: np.ndarray) -> tuple[int, np.ndarray]:
        env_outer, env_inner, self_outer, self_inner = self._sphere_gaps_np(q)
        if (env_inner < 0.0).any() or (self_inner < 0.0).any():
            return COLLIDING, np.zeros((0, 3), dtype=np.int64)
        pairs = [
            (0, g, k)
            for g, k in sorted({(int(self.spheres.geom[s]), int(k)) for s, k in zip(*np.nonzero(env_outer < 0.0))})
        ]
        pairs += [(1, *self.self_pairs[p]) for p in sorted(set(self._sphere_pairs[self_outer < 0.0, 2].tolist()))]
        if not pairs:
            return VALID, np.zeros((0, 3), dtype=np.int64)
        return AMBIGUOUS, np.array(pairs, dtype=np.int64)

    def _pair_gaps(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Smallest outer-sphere gap per (group, obstacle) and per self-collision group pair."""
        groups = self.spheres.geom
        env = np.full((self.spheres.n_groups, len(self.primitives.names)), np.inf)
        if self.use_numba:
            world = self.sphere_centers(q)
            dist = sphere_obstacle_distances_nb(world, self._packed_scene) if self.primitives.names else None
            if dist is not None:
                dist[self.spheres.joint == 0] = np.inf
                env_outer = dist - self.spheres.radius[:, None] - self.padding
            r = self.spheres.radius
            a, b, p = self._sphere_pairs.T
            self_outer = np.linalg.norm(world[a] - world[b], axis=-1) - r[a] - r[b] - self.padding
        else:
            env_outer, _, self_outer, _ = self._sphere_gaps_np(q)
            p = self._sphere_pairs[:, 2]
        if self.primitives.names:
            np.minimum.at(env, groups, env_outer)
        self_gap = np.full(len(self.self_pairs), np.inf)
        if len(self._sphere_pairs):
            np.minimum.at(self_gap, p, self_outer)
        return env, self_gap


def _with_hull(shape, placement) -> tuple:
    """(shape, its convex hull if a mesh else itself, placement)."""
    return shape, hull_or_self(shape), placement


def _coal_tf(rot: np.ndarray, pos: np.ndarray):
    return coal.Transform3s(np.ascontiguousarray(rot, dtype=float), np.ascontiguousarray(pos, dtype=float))


@dataclass(frozen=True)
class PathVerification:
    """Outcome of re-checking a path on the exact model."""

    valid: bool
    first_invalid_segment: int  # index i of the first failing segment path[i] -> path[i+1]; -1 if valid
    states_checked: int


def densify(path: np.ndarray, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """States along a piecewise-linear joint path, no joint moving more than ``resolution`` between two.

    Returns the states (start included) and, per state, the index of the segment it ends.
    """
    path = np.atleast_2d(np.asarray(path, dtype=float))
    states, segment = [path[:1]], [np.array([0])]
    for i in range(len(path) - 1):
        n = max(1, int(np.ceil(np.max(np.abs(path[i + 1] - path[i])) / resolution)))
        t = np.arange(1, n + 1)[:, None] / n
        states.append(path[i] + t * (path[i + 1] - path[i]))
        segment.append(np.full(n, i))
    return np.concatenate(states), np.concatenate(segment)


def verify_path(exact_checker, path, resolution: float = 0.01) -> PathVerification:
    """Re-check a full-configuration path with ``exact_checker`` at an L∞ step of ``resolution`` rad.

    One ``first_invalid`` call for the whole densified path (the exact checker's batch entry point).
    """
    if resolution <= 0:
        raise ValueError(f"resolution must be > 0, got {resolution}")
    states, segment = densify(path, resolution)
    idx = int(exact_checker.first_invalid(states))
    if idx < 0:
        return PathVerification(True, -1, len(states))
    return PathVerification(False, int(segment[idx]), idx + 1)
