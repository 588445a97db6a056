"""Balls containing a robot's collision geometries: a cheap lower bound on their distances for certification.

:class:`SphereCover` takes the search's sphere model where its spheres provably contain a geometry (a mesh's
triangles by construction; a box, sphere or cylinder when :func:`solid_inside_spheres` proves its volume) and
:func:`solid_balls` elsewhere; :func:`cover_bounds_nb` evaluates the bound for (geometry, obstacle primitive) and
(geometry, geometry) pairs. The certification's row kernels (:mod:`.bounds`) use it before coal
(``docs/certification.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin
from numba import njit

from maru_planner.collision.kernels.fk import place_members, row_distance
from maru_planner.collision.kernels.primitives import obstacle_distance
from maru_planner.collision.sphere_model import SphereModel
from maru_planner.collision.sphere_model import bounding_sphere as balls_bound
from maru_planner.robot.model import RobotModel

DISTANCE_TOLERANCE = 1e-6  # m: coal's GJK tolerance; certification takes it off every bound and coal distance
#: An empty cover's arrays, in :func:`cover_bounds_nb`'s order (for callers compiled for both cases).
NO_COVER = (np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0), np.zeros(1, np.int64), np.zeros(0, np.int64),
            np.zeros((0, 3)), np.zeros(0), np.zeros(1, np.int64))  # fmt: skip
CLUSTER_BALLS = 6  # balls of a generated cover per cluster (the sphere model's own clustering)
MAX_SOLID_PARTS = 16  # pieces per axis of a box or cylinder covered by balls
MAX_REMEMBERED_COVERS = 4096  # solid_inside_spheres answers _model_covers keeps (by their inputs)
SOLID_COVERS: dict[bytes, bool] = {}


@njit(cache=True)
def cover_bounds_nb(rots, poss, rows, config_of, first, second, obstacle, enough, s_joint, s_center, s_radius,
                    c_start, c_joint, c_center, c_radius, g_clusters, primitive, box_c, box_r, box_h, sph_c, sph_r,
                    cyl_c, cyl_a, cyl_h, cyl_r, bound):  # fmt: skip
    """Raise ``bound`` of each of ``rows`` (sorted by configuration) to its pair's sphere-cover bound.

    Obstacle pair (geometry g, obstacle k): the least signed distance of g's spheres to k's primitive minus
    their radii; self pair: the least gap between the two geometries' spheres. ``rots``/``poss``: each
    configuration's joint world poses. A cluster whose bounding sphere cannot beat the best value so far is
    skipped (its spheres lie inside it), and so is one whose bound reaches the row's ``enough``: the row's bound
    is then at most that cluster's bound, exact below ``enough``. Balls are placed in the world when first used.
    """
    sphere_world = np.empty((s_center.shape[0], 3))
    cluster_world = np.empty((c_center.shape[0], 3))
    cluster_placed = np.zeros(g_clusters.shape[0] - 1, dtype=np.bool_)  # per geometry: its clusters placed
    balls_placed = np.zeros(c_center.shape[0], dtype=np.bool_)
    current = -1
    for r in rows:
        c = config_of[r]
        if c != current:
            cluster_placed[:] = False
            balls_placed[:] = False
            current = c
        rot, pos = rots[c], poss[c]
        g, h, best, skipped = first[r], second[r], np.inf, np.inf
        place_members(g, g_clusters, cluster_placed, rot, pos, c_joint, c_center, cluster_world)
        if not obstacle[r]:
            place_members(h, g_clusters, cluster_placed, rot, pos, c_joint, c_center, cluster_world)
        for ca in range(g_clusters[g], g_clusters[g + 1]):
            # centres by index, never row views: the views took more than half of this kernel's time
            if obstacle[r]:
                k = primitive[h]
                lower = obstacle_distance(cluster_world[ca, 0], cluster_world[ca, 1], cluster_world[ca, 2], k, box_c,
                                          box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                          cyl_r) - c_radius[ca]  # fmt: skip
                if lower >= best:
                    continue
                if lower >= enough[r]:
                    skipped = min(skipped, lower)
                    continue
                place_members(ca, c_start, balls_placed, rot, pos, s_joint, s_center, sphere_world)
                for sa in range(c_start[ca], c_start[ca + 1]):
                    d = obstacle_distance(sphere_world[sa, 0], sphere_world[sa, 1], sphere_world[sa, 2], k, box_c,
                                          box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                          cyl_r) - s_radius[sa]  # fmt: skip
                    best = min(best, d)
                continue
            for cb in range(g_clusters[h], g_clusters[h + 1]):
                lower = row_distance(cluster_world, ca, cluster_world, cb) - c_radius[ca] - c_radius[cb]
                if lower >= best:
                    continue
                if lower >= enough[r]:
                    skipped = min(skipped, lower)
                    continue
                place_members(ca, c_start, balls_placed, rot, pos, s_joint, s_center, sphere_world)
                place_members(cb, c_start, balls_placed, rot, pos, s_joint, s_center, sphere_world)
                for sa in range(c_start[ca], c_start[ca + 1]):
                    for sb in range(c_start[cb], c_start[cb + 1]):
                        gap = row_distance(sphere_world, sa, sphere_world, sb) - s_radius[sa] - s_radius[sb]
                        best = min(best, gap)
        bound[r] = max(bound[r], min(best, skipped) - DISTANCE_TOLERANCE)


def solid_inside_spheres(geometry: coal.CollisionGeometry, placement: pin.SE3, centers: np.ndarray,
                         radii: np.ndarray, cells: tuple[int, ...] = (4, 8, 16, 32)) -> bool:  # fmt: skip
    """Whether a box, sphere or cylinder (placed by ``placement`` in the spheres' frame) lies inside the union of
    the balls (``centers``, ``radii``): its bounding box is cut into n^3 cells (n from ``cells``, finest last) and
    each cell meeting the solid must have its 8 corners, hence the whole cell, in one ball."""
    local = (np.asarray(centers, dtype=float) - placement.translation) @ placement.rotation  # in the solid's frame
    radii = np.asarray(radii, dtype=float) + 1e-9  # rounding; the cover bound takes DISTANCE_TOLERANCE off anyway
    if isinstance(geometry, coal.Sphere):
        return bool((np.linalg.norm(local, axis=1) + geometry.radius <= radii).any())
    if isinstance(geometry, coal.Box):
        half = np.asarray(geometry.halfSide, dtype=float)
    elif isinstance(geometry, coal.Cylinder):
        half = np.array([geometry.radius, geometry.radius, geometry.halfLength])
    else:
        return False
    for n in cells:
        axes = [np.linspace(-h, h, n + 1) for h in half]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)  # (n+1, n+1, n+1, 3) corners
        # |corner - centre|² <= radius² as one matrix product (10x faster than the norms); the 1e-9 m rounding
        # slack of ``radii`` is far above this expansion's error
        square = (grid * grid).sum(axis=-1)[..., None] - 2.0 * grid @ local.T + (local * local).sum(axis=1)
        inside = square <= radii * radii  # (..., balls)
        corners = [inside[i : i + n, j : j + n, k : k + n] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
        cell_covered = np.logical_and.reduce(corners).any(axis=-1)  # (n, n, n)
        if isinstance(geometry, coal.Cylinder):  # a cell whose nearest point is off the disc needs no ball
            lo = np.maximum(np.minimum(np.abs(grid[:-1, :-1, :-1, :2]), np.abs(grid[1:, 1:, 1:, :2])), 0.0)
            across = np.sign(grid[:-1, :-1, :-1, :2]) != np.sign(grid[1:, 1:, 1:, :2])
            nearest = np.linalg.norm(np.where(across, 0.0, lo), axis=-1)
            cell_covered |= nearest > geometry.radius  # touching the rim still needs its ball
        if cell_covered.all():
            return True
    return False


@dataclass(frozen=True)
class SphereCover:
    """Balls containing each robot geometry, in its parent joint's frame: a lower bound on its distances.

    From the search's sphere model (:mod:`~maru_planner.collision.sphere_model`) where they contain the
    geometry: every triangle of a mesh lies in one of its spheres (coal measures a mesh as its triangles), and a
    box, sphere or cylinder counts when :func:`solid_inside_spheres` proves its volume lies in them (the fit
    covers a solid's surface only). Other boxes and cylinders get :func:`solid_balls`. The balls' distance to
    an obstacle's kernel primitive (which contains the obstacle) or to another geometry's balls never exceeds
    coal's distance.
    """

    covered: np.ndarray  # (robot geometries,) bool: its balls contain it (False: a shape with neither)
    arrays: tuple  # the ball and cluster arrays cover_bounds_nb takes, in its order

    @classmethod
    def of(cls, robot: RobotModel, spheres: SphereModel | None) -> SphereCover | None:
        """The cover of ``robot``'s geometries, from ``spheres`` where it holds them (ignored if it is another
        robot's; without it meshes stay uncovered). None when no geometry is covered."""
        geometries = robot.collision_model.geometryObjects
        if spheres is not None and tuple(spheres.group_names) != tuple(obj.name for obj in geometries):
            spheres = None
        covered = np.zeros(len(geometries), dtype=bool)
        balls: list[tuple[int, np.ndarray, np.ndarray]] = []  # per cluster: joint, centres, radii
        g_clusters = [0]
        for g, obj in enumerate(geometries):
            if spheres is not None and _model_covers(spheres, g, obj):
                covered[g] = True
                for c in range(spheres.group_clusters[g], spheres.group_clusters[g + 1]):
                    own = slice(spheres.cluster_start[c], spheres.cluster_start[c + 1])
                    balls.append((obj.parentJoint, spheres.center[own], spheres.radius[own]))
            elif (own_balls := solid_balls(obj.geometry)) is not None:
                covered[g] = True
                centers = own_balls[0] @ obj.placement.rotation.T + obj.placement.translation
                for k in range(0, len(centers), CLUSTER_BALLS):
                    balls.append((obj.parentJoint, centers[k : k + CLUSTER_BALLS], own_balls[1][k : k + CLUSTER_BALLS]))
            g_clusters.append(len(balls))
        if not covered.any():
            return None
        bounds = [balls_bound(c, r) for _, c, r in balls]
        arrays = (
            np.concatenate([np.full(len(r), j) for j, _, r in balls]), np.concatenate([c for _, c, _ in balls]),
            np.concatenate([r for _, _, r in balls]), np.cumsum([0] + [len(r) for _, _, r in balls]),
            np.array([j for j, _, _ in balls]), np.array([c for c, _ in bounds]).reshape(-1, 3),
            np.array([r for _, r in bounds]), np.array(g_clusters),
        )  # fmt: skip
        ints = (0, 3, 4, 7)
        return cls(covered, tuple(np.ascontiguousarray(a, dtype=np.int64 if i in ints else float)
                                  for i, a in enumerate(arrays)))  # fmt: skip


def _model_covers(spheres: SphereModel, g: int, obj: pin.GeometryObject) -> bool:
    """Whether the sphere model's spheres of geometry ``g`` hold all of it: a mesh's by construction, a solid's
    when :func:`solid_inside_spheres` proves it (remembered: every planner, worker and attachment of a robot asks
    again, and for Maru-1's 34 solids the proof takes ~0.9 s)."""
    if isinstance(obj.geometry, coal.BVHModelBase):
        return True
    mine = slice(spheres.group_start[g], spheres.group_start[g + 1])
    centers, radii = spheres.center[mine], spheres.radius[mine]
    key = b"".join(np.ascontiguousarray(a, dtype=float).tobytes()
                   for a in (_solid_size(obj.geometry), obj.placement.homogeneous, centers, radii))  # fmt: skip
    key = type(obj.geometry).__name__.encode() + key
    covered = SOLID_COVERS.get(key)
    if covered is None:  # planners of several threads may get here at once: each answer is the same
        covered = solid_inside_spheres(obj.geometry, obj.placement, centers, radii)
        if len(SOLID_COVERS) >= MAX_REMEMBERED_COVERS:
            SOLID_COVERS.clear()
        SOLID_COVERS[key] = covered
    return covered


def _solid_size(geometry: coal.CollisionGeometry) -> list[float]:
    """The dimensions :func:`solid_inside_spheres` reads (none for a shape it does not take)."""
    if isinstance(geometry, coal.Sphere):
        return [geometry.radius]
    if isinstance(geometry, coal.Box):
        return list(geometry.halfSide)
    if isinstance(geometry, coal.Cylinder):
        return [geometry.radius, geometry.halfLength]
    return []


def solid_balls(geometry: coal.CollisionGeometry) -> tuple[np.ndarray, np.ndarray] | None:
    """Balls (centres in the geometry's frame, radii) whose union contains a sphere, box or cylinder (None: another
    shape).

    A sphere is its own ball; a box is cut into sub-boxes about as long as its thinnest side, a cylinder into
    slices half its radius long: each piece lies in the ball through its corners (a slice: its rim).
    """
    if isinstance(geometry, coal.Sphere):
        return np.zeros((1, 3)), np.array([float(geometry.radius)])
    if isinstance(geometry, coal.Box):
        half = np.asarray(geometry.halfSide, dtype=float)
        parts = np.minimum(np.ceil(half / half.min()), MAX_SOLID_PARTS).astype(int)
        piece = half / parts
        axes = [np.linspace(-h + p, h - p, n) for h, p, n in zip(half, piece, parts, strict=True)]
        centers = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        return centers, np.full(len(centers), float(np.linalg.norm(piece)))
    if isinstance(geometry, coal.Cylinder):
        radius, half_length = float(geometry.radius), float(geometry.halfLength)
        parts = int(min(max(np.ceil(2.0 * half_length / radius), 1), MAX_SOLID_PARTS))
        piece = half_length / parts
        z = np.linspace(-half_length + piece, half_length - piece, parts)
        return np.c_[np.zeros((parts, 2)), z], np.full(parts, math.hypot(radius, piece))
    return None
