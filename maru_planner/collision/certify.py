"""Certified collision-free arm paths: continuous validation of straight joint-space segments.

The validation of ``hpp-core`` (HPP's continuous validation), on Pinocchio + coal. For every pair
the exact :class:`~maru_planner.collision.checker.CollisionChecker` checks (robot geometry vs
obstacle, and its SRDF-filtered self-collision pairs) two numbers decide:

- a lower bound ``d`` on the pair's distance at a configuration: a bounding-volume bound first
  (the geometry's bounding sphere against the obstacle's oriented bounding box, or two bounding
  spheres), then coal's distance to a mesh's convex hull, the exact coal distance only where the
  hull is within the margin;
- an upper bound ``M`` on how fast that distance can change along a segment:
  ``M = sum_j c_j |q1_j - q0_j|`` over the joints that move one body of the pair but not the other,
  ``c_j`` the largest distance from joint ``j``'s axis to any point of the body (revolute; a bound
  from the joint offsets down the chain plus the geometry's bounding radius, tightened on each piece
  with the configuration at its middle) or 1 (prismatic).

On ``q(t) = q0 + t (q1 - q0)``, a pair whose distance at ``t_m`` is ``d`` keeps more than
``margin`` of clearance for ``|t - t_m| < (d - margin) / M``. Each segment is bisected until those
intervals cover it (a proof) or the exact distance at a checked configuration is within the margin
(a counter-example). Bounding volumes only ever prove; exact geometry decides every failure.

With the search's sphere model (``spheres``; every triangle of a mesh lies in one of its spheres) a mesh's
pairs get a tighter bound before coal: its spheres' distance to the obstacle's primitive or to the other
mesh's spheres. Unproven pieces are split into dyadic pieces, so all pairs share their configurations.

Large scenes (``NEAR_PATH_MIN_OBSTACLES`` reachable obstacles or more, e.g. a point cloud as 1 cm
balls): each certification first keeps the obstacles some moving geometry may come within its margin
of -- on each segment, the geometry's bounding sphere at the middle grown by half the segment's motion
times its levers -- and proves only their pairs; obstacle pairs are measured by coal directly.
:func:`certify_and_repair` re-plans a failing segment locally. See ``docs/certification.md``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import coal
import numpy as np
import pinocchio as pin
from numba import njit

from maru_planner import errors
from maru_planner.collision.batch_fk import (
    KinematicTree,
    joint_pose_nb,
    joint_poses_nb,
    point_in_world,
    root_pose_nb,
    row_distance,
    sphere_centers_nb,
    tree_arrays,
)
from maru_planner.collision.checker import CollisionChecker, hull_or_self, robot_hull, self_collision_pairs
from maru_planner.collision.sphere_cover import (
    DISTANCE_TOLERANCE,
    NO_COVER,
    SphereCover,
    cover_bounds_nb,
)
from maru_planner.collision.sphere_model import SphereModel
from maru_planner.collision.spheres import ScenePrimitives
from maru_planner.collision.support_bounds import (
    HULL,
    NO_SHAPE,
    convex_bound,
    load_primitive,
    new_records,
    place_shape,
    robot_shape_records,
)
from maru_planner.robot.model import RobotModel
from maru_planner.scene import Obstacle, Scene

DEFAULT_SAFETY_MARGIN = 0.01  # m (PlannerConfig.safety_margin's default too)
UNBOUNDED = 1e6  # m: an obstacle bounding box this large is treated as infinite
SHARED_END = 1e-12  # rad: a segment's rest between its blends this short is their shared end (certify_path)
MIN_INTERVAL = 1e-9  # rad: a piece of segment this short that is still unproven fails as "unproven"
# An unproven end is split into up to this many dyadic pieces at once, each no longer than twice the radius its
# piece's middle proved (bisecting one level per round took ~10 rounds a path, each a batch's fixed cost; 16 rather
# than 8: in-process A/B, 8 rounds, median plan -0.10 ms on MotionBenchMaker and -0.11 ms on Maru-1)
MAX_SPLIT = 16
ROWS_FOR_ALL = 8  # rows per configuration from which a round poses every joint at once (_place_rows_nb)
# what the row kernel's GJK bound (support_bounds) is for a pair: none (coal measures it), a lower bound (a robot
# hull: coal's mesh is finer), the distance itself (primitives on both sides, exactly the pair's shapes)
MEASURE_NONE, MEASURE_BOUND, MEASURE_EXACT = 0, 1, 2
COVER_SLACK_SPLIT = 16  # see proves_too_little (2 x the MAX_SPLIT of 8 it was chosen with)
NEAR_PATH_MIN_OBSTACLES = 64  # reachable obstacles from which a certification only builds pairs for those near its path
NEAR_TABLES = 4  # pair tables of near obstacles kept (blends and repairs certify around the same path)
CLEARANCE_WINDOW = 0.05  # m: clearance() measures the obstacles whose bound is this close to the nearest one first
# m: a repair starts and ends at waypoints at least this clear even when the margin is less (a margin of 0 let it
# start at waypoints touching an obstacle, from which every local path grazed it again)
MIN_ANCHOR_CLEARANCE = 0.0025
REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


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


def bounding_sphere(geometry: coal.CollisionGeometry) -> tuple[np.ndarray, float]:
    """Centre (in the geometry's frame) and radius of a sphere containing ``geometry``."""
    if isinstance(geometry, coal.BVHModelBase):
        vertices = np.asarray(geometry.vertices(), dtype=float)
        center = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        return center, float(np.linalg.norm(vertices - center, axis=1).max())
    if isinstance(geometry, coal.Sphere):
        return np.zeros(3), float(geometry.radius)
    if isinstance(geometry, (coal.Cylinder, coal.Cone)):
        return np.zeros(3), float(math.hypot(geometry.radius, geometry.halfLength))
    geometry.computeLocalAABB()
    return np.asarray(geometry.aabb_center, dtype=float).copy(), float(geometry.aabb_radius)


def joint_levers(robot: RobotModel) -> np.ndarray:
    """(robot geometries, nq): the most any point of a geometry moves per unit motion of each joint.

    Revolute joint upstream of the geometry: its joint offsets down to the geometry's joint (plus
    the travel of prismatic joints in between, from the joint limits) plus the geometry's reach from
    its own joint origin -- a bound on the distance from the axis valid in every configuration.
    Prismatic: 1. Joints not upstream: 0.
    """
    model = robot.model
    offset = np.zeros(model.njoints)  # longest possible distance from a joint's origin to its parent's
    prismatic = np.zeros(model.njoints, dtype=bool)
    for j in range(1, model.njoints):
        kind, name, i = model.joints[j].shortname(), model.names[j], model.joints[j].idx_q
        if kind not in REVOLUTE + PRISMATIC:
            raise errors.InvalidRequest(f"joint {name!r} ({kind}): only revolute and prismatic joints are certified")
        offset[j] = np.linalg.norm(model.jointPlacements[j].translation)
        if kind in PRISMATIC:
            travel = max(abs(robot.lower_limits[i]), abs(robot.upper_limits[i]))
            if not math.isfinite(travel):
                raise errors.InvalidRequest(f"prismatic joint {name!r} needs finite limits to be certified")
            offset[j] += travel
            prismatic[j] = True
    geometries = robot.collision_model.geometryObjects
    levers = np.zeros((len(geometries), model.nq))
    for g, obj in enumerate(geometries):
        center, radius = bounding_sphere(obj.geometry)
        reach = float(np.linalg.norm(obj.placement.act(center))) + radius
        j = obj.parentJoint
        while j != 0:
            levers[g, model.joints[j].idx_q] = 1.0 if prismatic[j] else reach
            reach += offset[j]
            j = model.parents[j]
    return levers


def _joint_of_q(model: pin.Model, i: int) -> int:
    return next(j for j in range(1, model.njoints) if model.joints[j].idx_q == i)


def _downstream(robot: RobotModel, levers: np.ndarray) -> np.ndarray:
    """(geometries, nq, nq): ``[g, j, k]`` = lever of joint k on g if k is below joint j on g's chain, else 0."""
    model = robot.model
    out = np.zeros((levers.shape[0], model.nq, model.nq))
    for g, obj in enumerate(robot.collision_model.geometryObjects):
        chain = [model.joints[j].idx_q for j in model.supports[obj.parentJoint] if j > 0]  # root first
        for n, j in enumerate(chain):
            for k in chain[n + 1 :]:
                out[g, j, k] = levers[g, k]
    return out


def chord_deviation(times: np.ndarray, acceleration_bound: np.ndarray) -> np.ndarray:
    """Per joint, how far a curve sampled at ``times`` can leave the straight chords between its samples.

    ``acceleration_bound``: per joint, the largest |acceleration| along the curve. Linear interpolation
    error: ``a dt^2 / 8`` for the longest sample interval ``dt``. Pass it as ``deviation`` to
    :meth:`PathCertifier.certify_path` to certify the curve itself rather than its chords.
    """
    dt = float(np.max(np.diff(np.asarray(times, dtype=float)), initial=0.0))
    return np.abs(np.asarray(acceleration_bound, dtype=float)) * dt * dt / 8.0


@dataclass
class _Pairs:
    """The pairs to prove as arrays: (moving geometry, obstacle) for a list of obstacles, then the self pairs.

    Obstacle pairs are measured by coal directly (a Pinocchio geometry model of thousands of obstacles takes
    minutes to build: each added object resizes its pair matrix), self pairs through the robot's own model.
    """

    obstacles: list  # per obstacle: (geometry, its convex hull or itself, placement)
    self_pair: np.ndarray  # (P,) index into the robot model's collision pairs (-1 for an obstacle pair)
    has_hull: np.ndarray  # (P,) bool: a mesh in the pair (its hull distance is a cheaper lower bound)
    first: np.ndarray  # (P,) robot geometry
    second: np.ndarray  # (P,) robot geometry, or obstacle index (into the box arrays) for obstacle pairs
    obstacle: np.ndarray  # (P,) bool
    other: np.ndarray  # (P,) the second robot geometry of a self pair (the first for an obstacle pair)
    moves_first: np.ndarray  # (P, nq) bool: joints that move the first body but not the second
    moves_other: np.ndarray  # (P, nq) bool: joints that move the second (robot) body but not the first
    rate: np.ndarray  # (P, nq): distance change per unit |dq_j|
    gap: np.ndarray  # (P,): exact distance - bounding-volume bound is at most this
    box_center: np.ndarray  # (K, 3) obstacle bounding boxes in the world
    box_rot: np.ndarray  # (K, 3, 3)
    box_half: np.ndarray  # (K, 3)
    covered: np.ndarray  # (P,) bool: a sphere-cover bound applies (mesh geometries, bounded obstacle primitives)
    measure: np.ndarray  # (P,) MEASURE_*: what the row kernel's GJK bound (support_bounds) is for the pair
    primitives: tuple  # the obstacles' sphere-kernel primitives (boxes, spheres, cylinders) and each one's index

    @property
    def arrays(self) -> tuple:
        """The per-pair arrays :func:`_assess_rows_nb` takes, in its order."""
        return (self.first, self.second, self.obstacle, self.other, self.covered, self.measure, self.moves_first,
                self.moves_other, self.gap, self.box_center, self.box_rot, self.box_half)  # fmt: skip


@njit(cache=True)
def _poses_nb(configs, parent, kind, axis, prot, ppos, idx_q, joint, local, rots, poss, centers):
    """Per configuration: every joint's world pose (``rots``, ``poss``) and the world centres of the geometries'
    bounding spheres."""
    for i in range(configs.shape[0]):
        joint_poses_nb(configs[i], parent, kind, axis, prot, ppos, idx_q, rots[i], poss[i])
        sphere_centers_nb(rots[i], poss[i], joint, local, centers[i])


@njit(cache=True)
def _place_rows_nb(configs, config_of, pair, first, other, parent, kind, axis, prot, ppos, idx_q, joint, local, rots,
                   poss, centers, posed):  # fmt: skip
    """What each row uses at its configuration: the poses of the joints on the chains to its pair's geometries
    (``posed``) and their bounding-sphere centres. A later round's configuration serves a few rows, often on one
    arm: the other joints are left unposed (Maru-1 needs 43 % of its joint poses, the Panda 79 %). Configurations
    serving :data:`ROWS_FOR_ALL` rows each or more on average (a first round's: every pair) are posed whole."""
    if pair.shape[0] >= ROWS_FOR_ALL * configs.shape[0]:
        _poses_nb(configs, parent, kind, axis, prot, ppos, idx_q, joint, local, rots, poss, centers)
        posed[:] = True
        return
    placed = np.zeros((configs.shape[0], joint.shape[0]), dtype=np.bool_)
    chain = np.empty(parent.shape[0], dtype=np.int64)
    for c in range(configs.shape[0]):
        root_pose_nb(rots[c], poss[c])
        posed[c, 0] = True
    for r in range(pair.shape[0]):
        c = config_of[r]
        for g in (first[pair[r]], other[pair[r]]):
            if placed[c, g]:
                continue
            n, j = 0, joint[g]
            while not posed[c, j]:  # the unposed joints up the chain, then posed from the top down
                chain[n], n, j = j, n + 1, parent[j]
            for i in range(n - 1, -1, -1):
                joint_pose_nb(chain[i], configs[c], parent, kind, axis, prot, ppos, idx_q, rots[c], poss[c])
                posed[c, chain[i]] = True
            centers[c, g, 0], centers[c, g, 1], centers[c, g, 2] = point_in_world(rots[c], poss[c], joint, local, g)
            placed[c, g] = True


@njit(cache=True)
def _to_axis_nb(rot, pos, axis, q_joint, center, posed, out):
    """``out[k]``: the distance of ``center`` from the axis of the joint of q ``k`` (one configuration's poses; 0 for
    a joint not ``posed``, which does not move it)."""
    for k in range(q_joint.shape[0]):
        j = q_joint[k]
        if not posed[j]:
            out[k] = 0.0
            continue
        u0 = rot[j, 0, 0] * axis[j, 0] + rot[j, 0, 1] * axis[j, 1] + rot[j, 0, 2] * axis[j, 2]
        u1 = rot[j, 1, 0] * axis[j, 0] + rot[j, 1, 1] * axis[j, 1] + rot[j, 1, 2] * axis[j, 2]
        u2 = rot[j, 2, 0] * axis[j, 0] + rot[j, 2, 1] * axis[j, 1] + rot[j, 2, 2] * axis[j, 2]
        d0 = center[0] - pos[j, 0]
        d1 = center[1] - pos[j, 1]
        d2 = center[2] - pos[j, 2]
        along = d0 * u0 + d1 * u1 + d2 * u2
        out[k] = np.sqrt(max(d0 * d0 + d1 * d1 + d2 * d2 - along * along, 0.0))


@njit(cache=True)
def _volume_bounds_nb(centers, config_of, pair, first, second, obstacle, box_center, box_rot, box_half, radius, out):
    """Per row: its pair's bounding sphere(s) against the obstacle's bounding box or the other bounding sphere."""
    for r in range(pair.shape[0]):
        p, c = pair[r], config_of[r]
        g, h = first[p], second[p]
        if obstacle[p]:
            outside = 0.0
            for a in range(3):
                local = 0.0
                for b in range(3):
                    local += box_rot[h, b, a] * (centers[c, g, b] - box_center[h, b])
                excess = abs(local) - box_half[h, a]
                if excess > 0.0:
                    outside += excess * excess
            out[r] = np.sqrt(outside) - radius[g]
        else:
            out[r] = row_distance(centers[c], g, centers[c], h) - radius[g] - radius[h]


@njit(cache=True, inline="always")
def proves_too_little(slack, needed):
    """Whether a bound ``slack`` above the margin proves under 1/COVER_SLACK_SPLIT of a piece that needs ``needed``
    (half its length times its rate): then the next finer measure takes it (cover -> coal, hull -> mesh) rather than
    the splitting, which may never end where a bound touches the margin at one point (each piece's middle then
    proves less than its piece)."""
    return slack * COVER_SLACK_SPLIT < needed


@njit(cache=True)
def _assess_rows_nb(configs, config_of, seg, pair, half, run_arrays, pair_arrays, robot_arrays, cover_arrays,
                    shape_arrays, primitives, use_cover, margin, bound, rate, need, refine, measured):  # fmt: skip
    """Per row, at the middle of its piece (one call per round of :meth:`PathCertifier._check_rows`): its pair's
    margin on its segment, the rate (configuration-free, tightened at the middle where the bounding volumes fall
    short of it), ``need`` = margin + half * rate, the distance bound (bounding volumes, then the sphere cover where
    they fall short of ``need``), and whether coal is to refine the bound (module doc: where it may prove the row,
    and wherever the bounds leave no slack; on a covered pair only then). A row coal would refine whose pair's shapes
    the kernel holds (``measure``) gets GJK's separating-axis bound first (``support_bounds``; ``measured``): coal
    then only measures a mesh where its hull's bound leaves the row unproven, and an exact pair where the distance
    leaves no slack (coal's verdict fails the path)."""
    pair_margin, rate_free, motion, downstream = run_arrays
    first, second, obstacle, other, covered, measure, moves_first, moves_other, gap, box_center, box_rot, box_half = (
        pair_arrays)
    parent, kind, axis, prot, ppos, idx_q, g_joint, g_local, g_radius, q_joint, levers, prismatic = robot_arrays
    n_rows, n_geoms, nq, n_configs = seg.shape[0], g_joint.shape[0], q_joint.shape[0], configs.shape[0]
    rots, poss = np.empty((n_configs, parent.shape[0], 3, 3)), np.empty((n_configs, parent.shape[0], 3))
    centers = np.empty((n_configs, n_geoms, 3))
    posed = np.zeros((n_configs, parent.shape[0]), dtype=np.bool_)
    _place_rows_nb(configs, config_of, pair, first, other, parent, kind, axis, prot, ppos, idx_q, g_joint, g_local,
                   rots, poss, centers, posed)  # fmt: skip
    volume = np.empty(n_rows)
    _volume_bounds_nb(centers, config_of, pair, first, second, obstacle, box_center, box_rot, box_half, g_radius,
                      volume)  # fmt: skip
    for r in range(n_rows):
        s, p = seg[r], pair[r]
        margin[r] = pair_margin[s, p]
        bound[r] = volume[r]
        rate[r] = rate_free[s, p]
        need[r] = margin[r] + half[r] * rate[r]
    to_axis = np.empty((n_configs, n_geoms, nq))
    has_axis = np.zeros((n_configs, n_geoms), dtype=np.bool_)
    for r in range(n_rows):
        s, p, c = seg[r], pair[r], config_of[r]
        if bound[r] < need[r]:  # tighten the levers with the configuration at the middle
            g, o, total = first[p], other[p], 0.0
            for b in (g, o):
                if not has_axis[c, b]:
                    _to_axis_nb(rots[c], poss[c], axis, q_joint, centers[c, b], posed[c], to_axis[c, b])
                    has_axis[c, b] = True
            for j in range(nq):
                lever = 0.0
                if moves_first[p, j]:
                    lever += 1.0 if prismatic[j] else min(
                        levers[g, j], to_axis[c, g, j] + g_radius[g] + half[r] * downstream[s, g, j])
                if moves_other[p, j]:
                    lever += 1.0 if prismatic[j] else min(
                        levers[o, j], to_axis[c, o, j] + g_radius[o] + half[r] * downstream[s, o, j])
                total += lever * motion[s, j]
            rate[r] = total
        need[r] = margin[r] + half[r] * rate[r]
    # the cover after the levers: it stops at the (lower) need they leave, and only where the volumes fall short of it
    n_cover = 0
    cover_rows = np.empty(n_rows, dtype=np.int64)
    for r in range(n_rows):
        if use_cover and covered[pair[r]] and bound[r] < need[r]:
            cover_rows[n_cover] = r
            n_cover += 1
    if n_cover:
        rows = cover_rows[:n_cover]
        rows = rows[np.argsort(config_of[rows])]
        cover_bounds_nb(rots, poss, rows, config_of, first[pair], second[pair], obstacle[pair], need, *cover_arrays,
                        *primitives, bound)  # fmt: skip
    # where coal would measure the pair: GJK's bound on the shapes the kernel holds instead
    g_kind, g_rot, g_pos, g_size, g_verts, verts = shape_arrays
    primitive, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r = primitives
    kinds, cs, rs, ss, vr = new_records()
    for r in range(n_rows):
        p = pair[r]
        no_slack = bound[r] <= margin[r]
        thin = proves_too_little(bound[r] - margin[r], half[r] * rate[r])
        refine[r] = bound[r] < need[r] and (volume[r] + gap[p] >= need[r] or no_slack) and (
            no_slack or thin or not covered[p])
        measured[r] = refine[r] and measure[p] != MEASURE_NONE
        if not measured[r]:
            continue
        c, g = config_of[r], first[p]
        place_shape(g, rots[c, g_joint[g]], poss[c, g_joint[g]], g_kind, g_rot, g_pos, g_size, g_verts, 0, kinds, cs,
                    rs, ss, vr)  # fmt: skip
        if obstacle[p]:
            load_primitive(primitive[second[p]], box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, 1,
                           kinds, cs, rs, ss)  # fmt: skip
        else:
            o = second[p]
            place_shape(o, rots[c, g_joint[o]], poss[c, g_joint[o]], g_kind, g_rot, g_pos, g_size, g_verts, 1, kinds,
                        cs, rs, ss, vr)  # fmt: skip
        lower = convex_bound(kinds, cs, rs, ss, vr, verts, need[r] + DISTANCE_TOLERANCE, centers[c, g])
        bound[r] = max(bound[r], lower - DISTANCE_TOLERANCE)
        no_slack = bound[r] <= margin[r]
        finer = measure[p] == MEASURE_BOUND and proves_too_little(bound[r] - margin[r], half[r] * rate[r])
        refine[r] = bound[r] < need[r] and (no_slack or finer)


FAILURE_REASONS = ("collision", "margin", "unproven", "timeout")  # Certificate.reason by the round kernels' codes


@njit(cache=True)
def _round_configs_nb(path, delta, bend, seg, a, b):
    """The middle of each row's piece: (distinct configurations in key order, each row's configuration, half
    the piece). Rows at the same segment and middle share one configuration (as ``np.unique`` would sort them).
    Segment s at t is ``path[s] + t * delta[s] + t² * bend[s]``."""
    n = seg.shape[0]
    half = np.empty(n)
    keys = np.empty(n)
    in_order = True
    for r in range(n):
        half[r] = 0.5 * (b[r] - a[r])
        keys[r] = seg[r] + 0.25 * (a[r] + b[r])
        in_order = in_order and (r == 0 or keys[r] >= keys[r - 1])
    # a first round's rows come segment by segment: sorting them would take 4x the rest of this kernel
    order = np.arange(n) if in_order else np.argsort(keys, kind="mergesort")
    config_of = np.empty(n, dtype=np.int64)
    firsts = np.empty(n, dtype=np.int64)
    count = 0
    for i in range(n):
        r = order[i]
        if i == 0 or keys[r] != keys[order[i - 1]]:
            firsts[count] = r
            count += 1
        config_of[r] = count - 1
    configs = np.empty((count, path.shape[1]))
    for c in range(count):
        r = firsts[c]
        mid = 0.5 * (a[r] + b[r])
        for j in range(path.shape[1]):
            configs[c, j] = path[seg[r], j] + mid * delta[seg[r], j] + mid * mid * bend[seg[r], j]
    return configs, config_of, half


@njit(cache=True)
def _fail_nb(segment, reason, config, alive, curve, failure, witness):
    """Segment ``segment`` fails: the rest of its curve needs no more proof; the first failure is kept
    (``failure``: [segment, reason code], ``witness``: its configuration)."""
    for s in range(segment, alive.shape[0]):
        if curve[s] == curve[segment]:
            alive[s] = False
    if segment < failure[0]:
        failure[0], failure[1] = segment, reason
        witness[:] = config


@njit(cache=True)
def _finish_round_nb(configs, config_of, seg, pair, a, b, half, margin, bound, rate, need, refine, exact, span,
                     timed_out, min_interval, max_split, alive, curve, clearance, failure, witness):  # fmt: skip
    """After a round's bounds (:meth:`PathCertifier._check_rows`): each segment's clearance, the failures, and the
    rows still unproven, as (seg, pair, a, b) of the next round.

    At the middle of its piece ``[a, b]`` a row's pair is proven for ``|t - m| <= (bound - margin) / rate``; each
    unproven end of the piece is widened to the dyadic piece that holds it, so that the pieces of all pairs share
    their middles, hence their forward kinematics (4x fewer configurations), and cut into up to ``max_split`` equal
    dyadic pieces, none longer than twice that radius where it can (a row near an obstacle skips the levels that
    one halving per round would spend a round each on).
    """
    n = seg.shape[0]
    for r in range(n):
        if refine[r] or bound[r] >= need[r]:
            clearance[seg[r]] = min(clearance[seg[r]], bound[r])
    for r in range(n):
        if exact[r] and bound[r] - margin[r] <= 0.0:
            _fail_nb(seg[r], 0 if bound[r] <= 0.0 else 1, configs[config_of[r]], alive, curve, failure, witness)
    reach = np.empty(n)
    open_ = np.zeros(n, dtype=np.bool_)
    for r in range(n):
        slack = max(bound[r] - margin[r], 0.0)
        reach[r] = slack / rate[r] if rate[r] > 0.0 else np.inf
        open_[r] = reach[r] < half[r] and alive[seg[r]]
    for r in range(n):
        if open_[r]:
            short = half[r] * span[seg[r]] < min_interval
            if short or timed_out:
                _fail_nb(seg[r], 2 if short else 3, configs[config_of[r]], alive, curve, failure, witness)
    size, step = np.empty(n), np.empty(n)
    count = 0
    for r in range(n):
        if open_[r] and alive[seg[r]]:
            size[r] = min(half[r], 2.0 ** np.ceil(np.log2(half[r] - reach[r])))
            step[r] = size[r]
            while step[r] > 2.0 * reach[r] and step[r] > size[r] / max_split:
                step[r] *= 0.5
            count += 2 * int(round(size[r] / step[r]))
    seg2, pair2 = np.empty(count, dtype=np.int64), np.empty(count, dtype=np.int64)
    a2, b2 = np.empty(count), np.empty(count)
    k = 0
    for r in range(n):
        if open_[r] and alive[seg[r]]:
            for start in (a[r], b[r] - size[r]):
                for i in range(int(round(size[r] / step[r]))):
                    seg2[k], pair2[k] = seg[r], pair[r]
                    a2[k] = start + i * step[r]
                    b2[k] = a2[k] + step[r]
                    k += 1
    return seg2, pair2, a2, b2


class _Run:
    """The state of one :meth:`PathCertifier.certify_path` call."""

    def __init__(self, path: np.ndarray, pairs: _Pairs, pair_margin: np.ndarray, deadline: float, downstream,
                 curve: np.ndarray, bend: np.ndarray):  # fmt: skip
        """``pair_margin`` (segments, pairs); ``curve`` (segments,): the curve each segment belongs to, -1 for a
        segment not to certify (between two curves); ``bend`` (segments, nq): segment s at t in [0, 1] is
        ``(1 - t) * path[s] + t * path[s + 1] + (t² - t) * bend[s]`` (zeros: straight)."""
        self.path, self.pairs, self.pair_margin, self.deadline = path, pairs, pair_margin, deadline
        self.curve = curve
        self.n_segments = len(path) - 1
        self.bend = np.ascontiguousarray(bend, dtype=float)
        self.delta = np.diff(path, axis=0) - self.bend  # segment s at t: path[s] + t * delta[s] + t² * bend[s]
        # (segments, nq): the largest |dq_j / dt| on each segment (at one of its ends: dq/dt is linear in t)
        self.motion = np.maximum(np.abs(self.delta), np.abs(self.delta + 2.0 * self.bend))
        self.span = self.motion.max(axis=1, initial=0.0)
        self.rate = self.motion @ pairs.rate.T  # (segments, pairs): configuration-free bound on distance change
        # (segments, geometries, nq): how fast a geometry can move relative to each joint's axis (joints below it)
        g, nq = downstream.shape[:2]
        self.downstream = (downstream.reshape(g * nq, nq) @ self.motion.T).T.reshape(-1, g, nq)  # einsum: 20x slower
        self.arrays = tuple(np.ascontiguousarray(a, dtype=float)
                            for a in (pair_margin, self.rate, self.motion, self.downstream))  # fmt: skip
        self.clearance = np.full(self.n_segments, math.inf)
        self.failure = np.array([self.n_segments, -1], dtype=np.int64)  # first failing segment, reason code
        self.witness_config = np.zeros(path.shape[1])
        self.alive = curve >= 0  # segments still worth proving: not after a failure on their curve
        n_pairs = len(pairs.first)
        # Pending work, one row per (segment, pair, piece [a, b] of the segment not yet proven for the pair).
        live = np.flatnonzero(self.alive)
        self.seg = np.repeat(live, n_pairs)
        self.pair = np.tile(np.arange(n_pairs), len(live))
        self.a, self.b = np.zeros(len(self.seg)), np.ones(len(self.seg))

    @property
    def failed(self) -> int:
        """The first failing segment (``n_segments``: none)."""
        return int(self.failure[0])

    @property
    def reason(self) -> str:
        return FAILURE_REASONS[self.failure[1]] if self.failure[1] >= 0 else ""

    @property
    def witness(self) -> np.ndarray | None:
        return self.witness_config.copy() if self.failure[1] >= 0 else None

    def failed_curves(self, n_curves: int) -> np.ndarray:
        """(n_curves,) bool: whether each curve has a failing segment."""
        out = np.zeros(n_curves, dtype=bool)
        done = (self.curve >= 0) & ~self.alive
        out[self.curve[done]] = True
        return out


class PathCertifier:
    """Certifies straight joint-space segments and paths on the exact checker's geometry (module doc).

    ``scene_or_checker``: a :class:`CollisionChecker` (its scene and pairs are followed as they change)
    or a :class:`Scene` (an exact checker is built on it). ``safety_margin`` (m, >= 0): the clearance a
    certified path keeps from every checked pair. ``spheres``: a sphere model of ``robot`` (the search's)
    whose cover of its meshes tightens their bounds (:class:`_SphereCover`). Not thread-safe (one Pinocchio
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
        self._q_joint = np.array([_joint_of_q(robot.model, i) for i in range(robot.nq)], dtype=np.int64)
        self._prismatic = np.array([robot.model.joints[int(j)].shortname() in PRISMATIC for j in self._q_joint])
        self._downstream = _downstream(robot, self._levers)
        self._robot_pairs = self_collision_pairs(robot)
        self._geoms = self._robot_geometry(lambda g: geometries[g].geometry)
        self._hull_geoms = self._robot_geometry(lambda g: self._hulls.get(g, geometries[g].geometry))
        self._query = (coal.DistanceRequest(), coal.DistanceResult())  # reused (cleared): making them costs like GJK
        self._pairs: _Pairs | None = None
        self._pairs_owner: list | None = None  # the reachable-obstacle list _pairs was built from
        self._near_tables: dict[bytes, _Pairs] = {}  # by the near obstacles' indices into _near_owner
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
            points, stride = _without_corners(path, np.asarray(corner_blends, dtype=float)), 2
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
    ) -> tuple[Certificate, _Run]:
        """Prove the segments of ``path`` (deviation (segments, nq), ``curve`` and ``bend`` as :class:`_Run` takes
        them; ``bend`` None: straight segments)."""
        bend = np.zeros((max(len(path) - 1, 0), self._model.nq)) if bend is None else bend
        # A bent segment stays within |bend| / 4 of its chord, the reach of the obstacles to consider
        pairs = self._pair_table(self._swept_reach(path, margin, deviation + 0.25 * np.abs(bend)))
        pair_margin = margin + deviation @ pairs.rate.T  # (segments, pairs)
        cert = Certificate(valid=True, margin=margin)
        run = _Run(path, pairs, pair_margin, math.inf if deadline is None else deadline, self._downstream, curve, bend)
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
    def _check_rows(self, run: _Run, cert: Certificate) -> None:
        """Evaluate every pending row at the middle of its piece at once; queue the parts still unproven.

        At the middle ``m`` of its piece ``[a, b]`` a row's pair is proven for ``|t - m| <= (d - margin) / rate``;
        what that radius leaves of ``[a, b]`` goes back to the queue as dyadic pieces. Rows at the same
        configuration share its forward kinematics.
        """
        seg, pair = run.seg, run.pair
        configs, config_of, half = _round_configs_nb(run.path, run.delta, run.bend, seg, run.a, run.b)
        cert.checks += len(configs)
        n_rows = len(seg)
        margin, bound, rate, need = (np.empty(n_rows) for _ in range(4))
        refine, measured = np.empty(n_rows, dtype=bool), np.empty(n_rows, dtype=bool)
        _assess_rows_nb(configs, config_of, seg, pair, half, run.arrays, run.pairs.arrays, self._robot_arrays,
                        self._cover_arrays, self._shape_arrays, run.pairs.primitives, self._cover is not None, margin,
                        bound, rate, need, refine, measured)  # fmt: skip
        exact = self._refine(configs, run.pairs, config_of, pair, refine, measured, margin, bound, need, cert)
        run.seg, run.pair, run.a, run.b = _finish_round_nb(
            configs, config_of, seg, pair, run.a, run.b, half, margin, bound, rate, need, refine | measured, exact,
            run.span, time.monotonic() > run.deadline, MIN_INTERVAL, MAX_SPLIT, run.alive, run.curve, run.clearance,
            run.failure, run.witness_config,
        )  # fmt: skip

    def _centers(self, configs: np.ndarray) -> np.ndarray:
        """The geometries' bounding-sphere centres at each configuration (C, geometries, 3), in one numba call."""
        n = len(configs)
        centers = np.empty((n, self._n_robot, 3))
        _poses_nb(configs, *self._tree, self._joint, self._local, np.empty((n, self._model.njoints, 3, 3)),
                  np.empty((n, self._model.njoints, 3)), centers)  # fmt: skip
        return centers

    def _warm_row_kernel(self) -> None:
        """Compile (or load) the row kernels for this robot's array types, on no rows (not in a request's budget)."""
        nq, n_geoms, none, no = self._model.nq, self._n_robot, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
        run_arrays = (np.zeros((0, 0)), np.zeros((0, 0)), np.zeros((0, nq)), np.zeros((0, n_geoms, nq)))
        pair_arrays = (none, none, no, none, no, none, np.zeros((0, nq), dtype=bool), np.zeros((0, nq), dtype=bool),
                       np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3)))  # fmt: skip
        _assess_rows_nb(np.zeros((1, nq)), none, none, none, np.zeros(0), run_arrays, pair_arrays, self._robot_arrays,
                        self._cover_arrays, self._shape_arrays, _kernel_primitives([])[0], self._cover is not None,
                        np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), no, no)  # fmt: skip
        _volume_bounds_nb(np.zeros((1, n_geoms, 3)), none, none, *pair_arrays[:3], *pair_arrays[9:], self._radius,
                          np.zeros(0))  # fmt: skip  # clearance() calls it from Python
        proves_too_little(0.0, 0.0)  # so does _refine
        path, rows = np.zeros((2, nq)), np.zeros(0)
        configs, config_of, half = _round_configs_nb(path, np.diff(path, axis=0), np.zeros((1, nq)), none, rows, rows)
        _finish_round_nb(configs, config_of, none, none, rows, rows, half, rows, rows, rows, rows, no, no, np.zeros(1),
                         False, MIN_INTERVAL, MAX_SPLIT, np.ones(1, dtype=bool), np.zeros(1, dtype=np.int64),
                         np.zeros(1), np.array([1, -1], dtype=np.int64), np.zeros(nq))  # fmt: skip

    def _bounds(self, centers: np.ndarray, pairs: _Pairs, config_of: np.ndarray, pair: np.ndarray) -> np.ndarray:
        """Bounding-volume lower bound of each row's pair distance at its configuration."""
        bound = np.empty(len(pair))
        _volume_bounds_nb(centers, config_of, pair, pairs.first, pairs.second, pairs.obstacle, pairs.box_center,
                          pairs.box_rot, pairs.box_half, self._radius, bound)  # fmt: skip
        return bound

    def _refine(self, configs, pairs: _Pairs, config_of, pair, refine, measured, margin, bound, need,
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

    def _distance(self, pairs: _Pairs, pair: int, hull: bool, placed: set[int]) -> float:
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

    def _pair_table(self, near: np.ndarray | None = None) -> _Pairs:
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
            hit = (_box_distances(centers[s], *subset) <= reach[s, :, None]).any(axis=0)
            near[candidates[hit]] = True
        return near

    def _box_bounds(self, q: np.ndarray) -> np.ndarray | None:
        """In a large scene (None otherwise), a lower bound of each reachable obstacle's distance to the robot at
        ``q`` (-inf for a half-space)."""
        boxes = self._obstacle_boxes()
        if boxes is None:
            return None
        centers = self._centers(q[None])
        gaps = _box_distances(centers[0, self._moving], *boxes) - self._radius[self._moving, None]
        return np.where(np.isfinite(boxes[2]).all(axis=1), gaps.min(axis=0, initial=math.inf), -math.inf)

    def _obstacle_boxes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(centres, rotations, half extents) of the reachable obstacles' bounding boxes in a large scene, else None."""
        if not self.near_path_only:
            return None
        obstacles = self.checker.reachable_obstacles
        if self._boxes is None or self._boxes[0] is not obstacles:
            boxes = [_bounding_box(ob.geometry(), pin.SE3(ob.pose[:3, :3].copy(), ob.pose[:3, 3].copy()))
                     for ob in obstacles]  # fmt: skip
            centers, rotations, halves = (np.array([box[i] for box in boxes], dtype=float) for i in range(3))
            self._boxes = (obstacles, (centers, rotations, halves))
        return self._boxes[1]

    def _build_pairs(self, obstacles: list[Obstacle]) -> _Pairs:
        """The table of ``obstacles`` (each against every moving geometry, in the exact checker's order) and the
        self pairs."""
        shapes = []
        for ob in obstacles:
            geometry = ob.geometry()
            shapes.append((geometry, hull_or_self(geometry), pin.SE3(ob.pose[:3, :3].copy(), ob.pose[:3, 3].copy())))
        boxes = [_bounding_box(geometry, placement) for geometry, _, placement in shapes]
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
        primitives, exact_primitive = _kernel_primitives(obstacles)
        kind = self._shape_arrays[0]
        held = np.concatenate([bounded[second[:n_env]], kind[second[n_env:]] != NO_SHAPE]) & (kind[first] != NO_SHAPE)
        exact = np.concatenate([exact_primitive[second[:n_env]], kind[second[n_env:]] != HULL]) & (kind[first] != HULL)
        return _Pairs(
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


def _kernel_primitives(obstacles: list[Obstacle]) -> tuple[tuple, np.ndarray]:
    """The obstacles' sphere-kernel primitives (each contains its obstacle): the index of each obstacle's
    primitive, then the arrays :func:`~maru_planner.collision.sphere_kernels.obstacle_distance` takes; and per
    obstacle whether its primitive is the obstacle itself."""
    primitives = ScenePrimitives.from_obstacles(obstacles)
    kernel_index = {id(ob): k for k, ob in enumerate(primitives.obstacles)}
    position = np.array([kernel_index[id(ob)] for ob in obstacles], dtype=np.int64)
    return (position, *primitives.as_tuple()[:-1]), primitives.exact[position]


def _box_distances(centers: np.ndarray, box_center: np.ndarray, box_rot: np.ndarray, box_half: np.ndarray
                   ) -> np.ndarray:  # fmt: skip
    """(points, boxes): distance from each of ``centers`` (n, 3) to each box (0 inside)."""
    offset = centers[:, None, :] - box_center[None]  # (points, boxes, 3)
    local = sum(offset[..., b, None] * box_rot[:, b] for b in range(3))  # R^T offset (5x faster than einsum here)
    return np.linalg.norm(np.maximum(np.abs(local) - box_half, 0.0), axis=2)


def _bounding_box(geometry: coal.CollisionGeometry, placement: pin.SE3
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:  # fmt: skip
    """World centre, rotation and half extents of a fixed obstacle's bounding box; True if it is the obstacle."""
    geometry.computeLocalAABB()
    lo, hi = np.asarray(geometry.aabb_local.min_, dtype=float), np.asarray(geometry.aabb_local.max_, dtype=float)
    if not (np.abs(lo).max() < UNBOUNDED and np.abs(hi).max() < UNBOUNDED):  # a half-space: coal decides each query
        return placement.translation.copy(), placement.rotation.copy(), np.full(3, np.inf), False
    return placement.act(0.5 * (lo + hi)), placement.rotation.copy(), 0.5 * (hi - lo), isinstance(geometry, coal.Box)


# ------------------------------------------------------------------ repair --
LocalPlanner = Callable[[np.ndarray, np.ndarray, float, float], np.ndarray | None]


@dataclass
class CertifiedPath:
    """Result of :func:`certify_and_repair`: the certified path (None if none could be made) and its cost."""

    path: np.ndarray | None
    certificate: Certificate  # the last certification; checks, exact queries and seconds summed over all
    repairs: int = 0  # local re-plans


def certify_and_repair(
    certifier: PathCertifier,
    path: np.ndarray,
    local_planner: LocalPlanner,
    deadline: float,
    *,
    margin: float | None = None,
    max_repairs: int = 3,
    certify_deadline: float | None = None,
    corner_blends: np.ndarray | None = None,
) -> CertifiedPath:
    """Certify ``path``; re-plan each failing segment locally (``local_planner``) until certified or out of tries.

    ``corner_blends`` (per waypoint, as :meth:`PathCertifier.certify_path` takes it): the corners a trajectory
    rounds with blends proven elsewhere are left out, until a repair changes the path (then all of it is certified
    again: its blends are to be proven anew).

    ``local_planner(qa, qb, margin, deadline)`` returns full configurations from ``qa`` to ``qb`` (None if it
    finds none); its path is certified like the rest. A failing segment is re-planned between the nearest
    waypoints around it that keep the margin, and at least :data:`MIN_ANCHOR_CLEARANCE`. ``margin`` (m; None =
    ``certifier.safety_margin``): a start or goal closer than that lowers the margin of this path to half its
    clearance (nothing nearer can be certified). Repairs stop at ``deadline``; certification itself at
    ``certify_deadline`` (None: no limit).
    """
    path = np.atleast_2d(np.asarray(path, dtype=float))
    margin = certifier.safety_margin if margin is None else float(margin)
    done, repairs, relaxed = 0, 0, False
    total = Certificate(valid=False, margin=margin)
    while True:
        blends = None if corner_blends is None else corner_blends[done:]
        cert = certifier.certify_path(path[done:], certify_deadline, margin=margin, corner_blends=blends)
        _accumulate(total, cert, done)
        if cert.valid:
            return CertifiedPath(path, total, repairs)
        if cert.reason == "margin" and not relaxed:
            relaxed = True
            ends = min(certifier.clearance(path[0]), certifier.clearance(path[-1]))
            if ends <= margin:
                margin, done = 0.5 * max(ends, 0.0), 0
                total.margin = margin
                continue
        if cert.reason == "timeout" or repairs >= max_repairs or time.monotonic() >= deadline:
            return CertifiedPath(None, total, repairs)
        a, b = _repair_anchors(certifier, path, total.first_failing_segment, max(margin, MIN_ANCHOR_CLEARANCE))
        repairs += 1
        local = local_planner(path[a], path[b], margin, deadline)
        if local is None:
            return CertifiedPath(None, total, repairs)
        path, done = np.vstack([path[:a], np.atleast_2d(local), path[b + 1 :]]), a
        if corner_blends is not None:  # the corners certified without their blends' ends change: all of it again
            corner_blends, done = None, 0


def _without_corners(path: np.ndarray, corner_blends: np.ndarray) -> np.ndarray:
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


def _repair_anchors(certifier: PathCertifier, path: np.ndarray, segment: int, margin: float) -> tuple[int, int]:
    """Waypoint indices around ``segment`` that keep more than ``margin`` (the path's ends at the latest)."""
    a, b = segment, segment + 1
    while a > 0 and certifier.clearance(path[a]) <= margin:
        a -= 1
    while b < len(path) - 1 and certifier.clearance(path[b]) <= margin:
        b += 1
    return a, b


def _accumulate(total: Certificate, cert: Certificate, offset: int) -> None:
    """Fold the certificate of ``path[offset:]`` into ``total`` (the whole path's; costs summed)."""
    total.valid, total.reason, total.witness = cert.valid, cert.reason, cert.witness
    total.first_failing_segment = cert.first_failing_segment + offset if not cert.valid else -1
    total.segment_clearance = total.segment_clearance[:offset] + cert.segment_clearance
    total.min_clearance = min(total.segment_clearance, default=math.inf) if cert.valid else cert.min_clearance
    total.checks += cert.checks
    total.exact_queries += cert.exact_queries
    total.hull_queries += cert.hull_queries
    total.seconds += cert.seconds
