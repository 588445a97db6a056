"""Spheres that cover a robot's collision geometry, fitted once per model.

Each collision geometry object of a pinocchio ``GeometryModel`` (box, cylinder, capsule, sphere,
convex or triangle mesh) is replaced by a few spheres fixed in its parent joint frame.

Conservative by construction, for the surface: the geometry's surface is cut into small triangles
(boxes and meshes exactly; a cylinder via a circumscribed prism) and every triangle is assigned to
one sphere that contains its three vertices, hence the whole triangle (a ball is convex). So every
surface point of the real link lies inside some sphere. An obstacle that overlaps the link either
crosses its surface, which the spheres cover, or lies entirely inside the link, which cannot happen
for solid obstacles larger than the link's interior. Capsules and spheres get exact coverings.

Centres: a greedy set cover (see :func:`cover_surface`) picks centres from a grid filling the
geometry's convex hull, deep points first in effect, so that no sphere protrudes from the hull by
much more than ``max_protrusion``; small geometries get one or two spheres, a Panda link 15-50.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import coal
import numpy as np
from scipy.spatial import ConvexHull, Delaunay

from maru_planner.robot.sphere_options import SphereFitOptions  # re-exported: its home is robot/ (profiles carry it)

FIT_VERSION = 5  # bump when the fit changes, so cached models are refitted


@dataclass(frozen=True)
class SphereModel:
    """Spheres grouped by collision geometry object, in their parent joint frames."""

    joint: np.ndarray  # (ns,) parent joint index of each sphere
    center: np.ndarray  # (ns, 3) centre in the parent joint frame
    radius: np.ndarray  # (ns,) outer radius: the spheres cover the geometry
    inner: np.ndarray  # (ns,) inner radius: the ball of this radius around the centre lies inside the geometry
    geom: np.ndarray  # (ns,) index of the geometry object (group) the sphere belongs to
    group_start: np.ndarray  # (ng + 1,) spheres of group g are group_start[g]:group_start[g + 1]
    group_joint: np.ndarray  # (ng,) parent joint of each geometry object
    group_center: np.ndarray  # (ng, 3) bounding sphere of the group, in the joint frame
    group_radius: np.ndarray  # (ng,)
    group_names: tuple[str, ...]  # geometry object names
    group_links: tuple[str, ...]  # parent frame (link) names
    # second level of the hierarchy: each group's spheres are sorted into clusters of a few spheres
    cluster_start: np.ndarray  # (nc + 1,) spheres of cluster c are cluster_start[c]:cluster_start[c + 1]
    cluster_joint: np.ndarray  # (nc,)
    cluster_center: np.ndarray  # (nc, 3) bounding sphere of the cluster, in the joint frame
    cluster_radius: np.ndarray  # (nc,)
    group_clusters: np.ndarray  # (ng + 1,) clusters of group g are group_clusters[g]:group_clusters[g + 1]

    @property
    def n_spheres(self) -> int:
        return len(self.radius)

    @property
    def n_groups(self) -> int:
        return len(self.group_joint)


def fit_sphere_model(model, collision_model, options: SphereFitOptions | None = None) -> SphereModel:
    """Fit covering spheres to every geometry object of ``collision_model`` (a pinocchio GeometryModel)."""
    options = options or SphereFitOptions()
    joints, centers, radii, inners, geoms, starts = [], [], [], [], [], [0]
    g_joint, g_center, g_radius, names, links = [], [], [], [], []
    c_start, c_joint, c_center, c_radius, g_clusters = [0], [], [], [], [0]
    for gi, obj in enumerate(collision_model.geometryObjects):
        c_local, r, r_in = fit_geometry(obj.geometry, options)
        rot, pos = obj.placement.rotation, obj.placement.translation
        c = c_local @ rot.T + pos
        order, sizes = cluster_spheres(c, options.cluster_size)
        c, r, r_in = c[order], r[order], r_in[order]
        for lo, hi in zip(np.cumsum([0, *sizes[:-1]]), np.cumsum(sizes)):
            bc, br = bounding_sphere(c[lo:hi], r[lo:hi])
            c_start.append(starts[-1] + int(hi))
            c_joint.append(obj.parentJoint)
            c_center.append(bc)
            c_radius.append(br)
        g_clusters.append(g_clusters[-1] + len(sizes))
        joints.append(np.full(len(r), obj.parentJoint))
        centers.append(c)
        radii.append(r)
        inners.append(np.minimum(r_in, r))
        geoms.append(np.full(len(r), gi))
        starts.append(starts[-1] + len(r))
        bc, br = bounding_sphere(c, r)
        g_joint.append(obj.parentJoint)
        g_center.append(bc)
        g_radius.append(br)
        names.append(obj.name)
        links.append(model.frames[obj.parentFrame].name if obj.parentFrame < len(model.frames) else obj.name)
    return SphereModel(
        joint=np.concatenate(joints).astype(np.int64),
        center=np.concatenate(centers),
        radius=np.concatenate(radii),
        inner=np.concatenate(inners),
        geom=np.concatenate(geoms).astype(np.int64),
        group_start=np.asarray(starts, dtype=np.int64),
        group_joint=np.asarray(g_joint, dtype=np.int64),
        group_center=np.asarray(g_center).reshape(-1, 3),
        group_radius=np.asarray(g_radius, dtype=float),
        group_names=tuple(names),
        group_links=tuple(links),
        cluster_start=np.asarray(c_start, dtype=np.int64),
        cluster_joint=np.asarray(c_joint, dtype=np.int64),
        cluster_center=np.asarray(c_center).reshape(-1, 3),
        cluster_radius=np.asarray(c_radius, dtype=float),
        group_clusters=np.asarray(g_clusters, dtype=np.int64),
    )


def cluster_spheres(centers: np.ndarray, size: int) -> tuple[np.ndarray, list[int]]:
    """Order of the spheres grouping them into clusters of about ``size`` near each other, and cluster sizes.

    Farthest-point seeds, then a few nearest-seed (Lloyd) rounds; deterministic.
    """
    n = len(centers)
    k = max(1, int(np.ceil(n / max(size, 1))))
    if k == 1:
        return np.arange(n), [n]
    seeds = [0]
    dist = np.linalg.norm(centers - centers[0], axis=1)
    for _ in range(k - 1):
        seeds.append(int(dist.argmax()))
        dist = np.minimum(dist, np.linalg.norm(centers - centers[seeds[-1]], axis=1))
    means = centers[seeds].copy()
    for _ in range(8):
        labels = np.linalg.norm(centers[:, None] - means[None], axis=2).argmin(axis=1)
        for j in range(k):
            if np.any(labels == j):
                means[j] = centers[labels == j].mean(axis=0)
    order = np.argsort(labels, kind="stable")
    sizes = [int(c) for c in np.bincount(labels, minlength=k) if c > 0]
    return order, sizes


def cache_dir() -> Path:
    """Where fitted sphere models are kept (``$MARU_PLANNER_CACHE`` or ``~/.cache/maru_planner``)."""
    return Path(os.environ.get("MARU_PLANNER_CACHE", Path.home() / ".cache" / "maru_planner")) / "spheres"


def geometry_fingerprint(collision_model, options: SphereFitOptions) -> str:
    """Hash of everything the fit depends on: shapes, their data, placements, parents and the options."""
    h = hashlib.sha1(f"{FIT_VERSION}|{dataclasses.astuple(options)!r}".encode())
    for obj in collision_model.geometryObjects:
        geometry = obj.geometry
        h.update(f"{obj.name}|{type(geometry).__name__}|{obj.parentJoint}|{obj.parentFrame}".encode())
        h.update(np.asarray(obj.placement.homogeneous, dtype=float).tobytes())
        for attr in ("radius", "halfLength", "halfSide"):
            if hasattr(geometry, attr):
                h.update(np.asarray(getattr(geometry, attr), dtype=float).tobytes())
        if hasattr(geometry, "vertices"):
            h.update(np.asarray(geometry.vertices(), dtype=float).tobytes())
        elif hasattr(geometry, "points"):
            h.update(np.asarray(geometry.points(), dtype=float).tobytes())
    return h.hexdigest()


def cached_path(collision_model, options: SphereFitOptions | None = None) -> Path:
    """Where :func:`load_or_fit` keeps the sphere model of ``collision_model`` (the file may not exist yet)."""
    return cache_dir() / f"{geometry_fingerprint(collision_model, options or SphereFitOptions())}.npz"


def first_fit_notice(name: str, collision_model, options: SphereFitOptions | None = None) -> str | None:
    """The line to show before building a sphere checker of robot ``name`` whose sphere model is not on disk yet
    (the fit takes ~20 s for a 7-link arm), else None."""
    path = cached_path(collision_model, options)
    if path.is_file():
        return None
    return (
        f"fitting the sphere model of {name} (first use of its geometry, ~20 s for a 7-link arm; kept in {path.parent})"
    )


def load_or_fit(model, collision_model, options: SphereFitOptions | None = None, use_cache: bool = True):
    """:func:`fit_sphere_model`, kept on disk at :func:`cached_path` (a fit takes ~20 s for a 7-link arm)."""
    options = options or SphereFitOptions()
    path = cached_path(collision_model, options)
    if use_cache and path.is_file():
        try:
            return _from_npz(path)
        except Exception:  # a truncated or stale file: fit again and overwrite it
            pass
    spheres = fit_sphere_model(model, collision_model, options)
    if use_cache:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
            arrays: dict[str, Any] = {f.name: np.asarray(getattr(spheres, f.name)) for f in dataclasses.fields(spheres)}
            np.savez(tmp, **arrays)
            os.replace(tmp, path)
        except OSError:
            pass
    return spheres


def _from_npz(path: Path) -> SphereModel:
    with np.load(path, allow_pickle=False) as data:
        values = {f.name: data[f.name] for f in dataclasses.fields(SphereModel)}
    values["group_names"] = tuple(str(x) for x in values["group_names"])
    values["group_links"] = tuple(str(x) for x in values["group_links"])
    if len(values["group_clusters"]) != len(values["group_joint"]) + 1:
        raise ValueError("stale sphere cache")
    return SphereModel(**values)


def bounding_sphere(centers: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, float]:
    """A sphere containing all given spheres (centred on their box's middle; not minimal)."""
    lo = (centers - radii[:, None]).min(axis=0)
    hi = (centers + radii[:, None]).max(axis=0)
    mid = 0.5 * (lo + hi)
    return mid, float(np.max(np.linalg.norm(centers - mid, axis=1) + radii))


def fit_geometry(geometry, options: SphereFitOptions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covering spheres (centres, outer radii, inner radii) of one coal geometry, in its own frame."""
    if isinstance(geometry, coal.Sphere):
        return np.zeros((1, 3)), np.array([geometry.radius]), np.array([geometry.radius])
    if isinstance(geometry, coal.Capsule):
        centers, radii = capsule_spheres(geometry.radius, geometry.halfLength, options.max_edge * 4)
        return centers, radii, np.full(len(radii), geometry.radius)
    vertices, triangles = surface_of(geometry, options)
    centers, radii = cover_surface(vertices, triangles, options)
    return centers, radii, inner_radii(geometry, centers, vertices)


def inner_radii(geometry, centers: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Radius of a ball around each centre that the exact checker would see as inside the geometry.

    Boxes, cylinders, spheres, convex shapes: exact (depth of the centre). Triangle meshes: 0. coal tests a
    mesh by its triangles, so for the exact model a mesh is its surface: an obstacle (or a hole in an open
    mesh) inside it is not a collision; no ball is certainly "in collision" then, and every contact near a
    mesh link is left to coal.
    """
    if isinstance(geometry, coal.Box):
        return np.maximum((np.asarray(geometry.halfSide) - np.abs(centers)).min(axis=1), 0.0)
    if isinstance(geometry, coal.Cylinder):
        radial = np.linalg.norm(centers[:, :2], axis=1)
        depth = np.minimum(geometry.radius - radial, geometry.halfLength - np.abs(centers[:, 2]))
        return np.maximum(depth, 0.0)
    if isinstance(geometry, coal.ConvexBase):
        return depth_in_hull(centers, vertices)
    return np.zeros(len(centers))


def surface_of(geometry, options: SphereFitOptions) -> tuple[np.ndarray, np.ndarray]:
    """A closed triangle surface (vertices, triangles) enclosing the geometry."""
    if isinstance(geometry, coal.Box):
        return box_surface(np.asarray(geometry.halfSide, dtype=float))
    if isinstance(geometry, coal.Cylinder):
        return cylinder_surface(geometry.radius, geometry.halfLength, options.cylinder_sides)
    if isinstance(geometry, coal.BVHModelBase):
        vertices = np.asarray(geometry.vertices(), dtype=float)
        tris = np.array([[t[0], t[1], t[2]] for t in (geometry.tri_indices(i) for i in range(geometry.num_tris))])
        return vertices, tris.reshape(-1, 3).astype(np.int64)
    if isinstance(geometry, coal.ConvexBase):
        points = np.asarray(geometry.points(), dtype=float)
        return points, ConvexHull(points).simplices.astype(np.int64)
    raise ValueError(f"cannot fit spheres to collision geometry of type {type(geometry).__name__}")


def box_surface(half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float) * half
    return corners, ConvexHull(corners).simplices.astype(np.int64)


def cylinder_surface(radius: float, half_length: float, sides: int) -> tuple[np.ndarray, np.ndarray]:
    """A prism with ``sides`` faces circumscribing the cylinder (its faces touch the circle)."""
    r_out = radius / np.cos(np.pi / sides)
    ang = 2 * np.pi * np.arange(sides) / sides
    ring = np.stack([r_out * np.cos(ang), r_out * np.sin(ang)], axis=1)
    points = np.concatenate([np.c_[ring, np.full(sides, -half_length)], np.c_[ring, np.full(sides, half_length)]])
    return points, ConvexHull(points).simplices.astype(np.int64)


def capsule_spheres(radius: float, half_length: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres on the capsule's axis; radius grown so consecutive spheres leave no gap at the surface."""
    n = max(2, int(np.ceil(2 * half_length / spacing)) + 1)
    z = np.linspace(-half_length, half_length, n)
    step = z[1] - z[0] if n > 1 else 0.0
    r = np.sqrt(radius**2 + (0.5 * step) ** 2)
    return np.c_[np.zeros((n, 2)), z], np.full(n, r)


def subdivide(vertices: np.ndarray, triangles: np.ndarray, max_edge: float) -> np.ndarray:
    """Corner points (t, 3, 3) of triangles split at edge midpoints until every edge is <= max_edge."""
    tri = vertices[triangles]
    done = []
    while len(tri):
        edges = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)
        small = edges.max(axis=1) <= max_edge
        done.append(tri[small])
        big = tri[~small]
        if not len(big):
            break
        a, b, c = big[:, 0], big[:, 1], big[:, 2]
        ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
        tri = np.concatenate(
            [np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))], axis=0
        )
    return np.concatenate(done, axis=0)


def interior_points(vertices: np.ndarray, step: float) -> np.ndarray:
    """Grid points inside the convex hull of ``vertices`` (at least the vertices' mean)."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    axes = [
        np.arange(lo[d] + 0.5 * step, hi[d], step) if hi[d] - lo[d] > step else np.array([0.5 * (lo[d] + hi[d])])
        for d in range(3)
    ]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    try:
        inside = grid[Delaunay(vertices).find_simplex(grid) >= 0]
    except Exception:  # flat or degenerate hull: every grid point is a candidate
        inside = grid
    return np.concatenate([inside, vertices.mean(axis=0, keepdims=True)])


def depth_in_hull(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Distance from each point to the boundary of the convex hull of ``vertices`` (0 outside)."""
    try:
        eq = ConvexHull(vertices).equations
    except Exception:
        return np.zeros(len(points))
    return np.maximum(-(points @ eq[:, :3].T + eq[:, 3]).max(axis=1), 0.0)


def corner_distances(corners: np.ndarray, centers: np.ndarray, chunk: int = 128) -> np.ndarray:
    """need[c, t]: radius a sphere at centres[c] needs to contain triangle t (its farthest corner)."""
    need = np.empty((len(centers), len(corners)), dtype=np.float32)
    for i in range(0, len(centers), chunk):
        diff = corners[None, :, :, :] - centers[i : i + chunk, None, None, :]
        need[i : i + chunk] = np.sqrt((diff * diff).sum(axis=3)).max(axis=2)
    return need


def cover_surface(vertices: np.ndarray, triangles: np.ndarray, options: SphereFitOptions):
    """Greedy set cover of the surface triangles by spheres that protrude at most ~``max_protrusion``.

    A candidate centre at depth ``d`` inside the hull may take radius ``d + max_protrusion``; the
    candidate containing the most still-uncovered triangles is taken, its radius shrunk to the
    farthest corner of the triangles it newly covers. Where no candidate can reach a triangle (sharp
    corners) the allowance grows by half until one can, so every triangle ends up covered.
    """
    corners = subdivide(vertices, triangles, options.max_edge)
    size = float((vertices.max(axis=0) - vertices.min(axis=0)).max())
    candidates = interior_points(vertices, min(options.grid_step, max(size / 6.0, 1e-4)))
    depth = depth_in_hull(candidates, vertices)
    need = corner_distances(corners, candidates)
    uncovered = np.ones(len(corners), dtype=bool)
    allowance = options.max_protrusion
    covers = need <= (depth + allowance)[:, None]
    centers, radii = [], []
    while uncovered.any():
        gain = covers[:, uncovered].sum(axis=1)
        best = int(gain.argmax())
        if gain[best] == 0:
            allowance *= 1.5
            covers = need <= (depth + allowance)[:, None]
            continue
        new = covers[best] & uncovered
        centers.append(candidates[best])
        radii.append(float(need[best, new].max()))
        uncovered &= ~new
    return np.asarray(centers), np.asarray(radii)
