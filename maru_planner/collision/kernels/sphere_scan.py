"""The sphere checker's kernel: a batch of configurations, robot spheres against the scene's primitives and against
each other (numba).

Two radii per robot sphere: the *outer* radius covers the link's surface (sphere_model), the *inner*
radius is a ball inside the link (its centre's depth in the convex link). Outer free -> free; inner
hit -> hit; between the two the exact model decides (spheres.py).

Broad phase: each geometry object's spheres have a bounding sphere; only when it is within reach of
an obstacle (or of the other group's bound, for self-collision pairs) are its spheres tested. In a
large scene the obstacles sit in a uniform grid (:func:`~.grid.build_grid`) and each group only meets the
obstacles listed in the cells its bounding sphere overlaps.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.kernels.fk import joint_poses_nb, sphere_centers_nb
from maru_planner.collision.kernels.grid import cell_range, unpack_grid
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, COLLIDING, VALID, point_obstacle_distance


@njit(cache=True, inline="always")
def _dist(a, b):
    d0, d1, d2 = a[0] - b[0], a[1] - b[1], a[2] - b[2]
    return np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


@njit(cache=True, inline="always")
def _place_spheres(c, c_start, placement, world):
    """World centres of cluster ``c``'s spheres into ``world``, unless they are for this state: ``placement`` is
    (sphere joints, local centres, joint rotations, joint positions, placed flags per cluster)."""
    s_joint, s_center, rot, pos, placed = placement
    if placed[c]:
        return
    placed[c] = True
    for s in range(c_start[c], c_start[c + 1]):
        j = s_joint[s]
        for a in range(3):
            world[s, a] = (pos[j, a] + rot[j, a, 0] * s_center[s, 0] + rot[j, a, 1] * s_center[s, 1]
                           + rot[j, a, 2] * s_center[s, 2])  # fmt: skip


@njit(cache=True)
def _scene_by_grid(
    padding, s_inner, s_radius, c_start, c_radius, g_joint, g_clusters, world, cworld, placement,
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact, grid_i, grid_f, amb, mark,
):  # fmt: skip
    """Robot-vs-scene part of :func:`classify_state` through the grid: the number of (group, obstacle) pairs
    written to ``amb``, or -1 when an inner ball is hit (COLLIDING).

    ``mark[0]`` drops an obstacle listed in several cells of one cluster's query, ``mark[1]`` a pair that
    several clusters of one group touch; their last entries are running tags.
    """
    n_obs = mark.shape[1] - 1
    nx, ny, nz = grid_i[0], grid_i[1], grid_i[2]
    cell_start, items, big = unpack_grid(grid_i)
    h, ox, oy, oz = grid_f[0], grid_f[1], grid_f[2], grid_f[3]
    near = np.empty(n_obs, dtype=np.int64)  # one cluster's obstacles, each once
    n_amb = 0
    for g in range(g_joint.shape[0]):
        if g_joint[g] == 0:  # fixed to the world: like the exact checker, never tested against the scene
            continue
        mark[1, n_obs] += 1
        pair_tag = mark[1, n_obs]
        for c in range(g_clusters[g], g_clusters[g + 1]):
            mark[0, n_obs] += 1
            tag = mark[0, n_obs]
            reach = c_radius[c] + padding
            i0, i1 = cell_range(cworld[c, 0] - reach, cworld[c, 0] + reach, ox, h, nx)
            j0, j1 = cell_range(cworld[c, 1] - reach, cworld[c, 1] + reach, oy, h, ny)
            l0, l1 = cell_range(cworld[c, 2] - reach, cworld[c, 2] + reach, oz, h, nz)
            n_near = 0
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    for l in range(l0, l1 + 1):
                        cell = (i * ny + j) * nz + l
                        for idx in range(cell_start[cell], cell_start[cell + 1]):
                            k = items[idx]
                            if mark[0, k] != tag:
                                mark[0, k] = tag
                                near[n_near] = k
                                n_near += 1
            for k in big:  # never listed in a cell
                near[n_near] = k
                n_near += 1
            # The cluster test written out, as in _scene_by_loop.
            for t in range(n_near):
                k = near[t]
                if point_obstacle_distance(cworld[c], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                           cyl_r) >= reach:  # fmt: skip
                    continue
                _place_spheres(c, c_start, placement, world)
                touched = False
                for s in range(c_start[c], c_start[c + 1]):
                    d = point_obstacle_distance(world[s], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                                cyl_r)  # fmt: skip
                    if exact[k] and d < s_inner[s] + padding:
                        return -1
                    if d < s_radius[s] + padding:
                        touched = True
                if touched and mark[1, k] != pair_tag and n_amb < amb.shape[0]:
                    mark[1, k] = pair_tag  # (g, k) once, whichever of g's clusters touch k
                    amb[n_amb, 0], amb[n_amb, 1], amb[n_amb, 2] = 0, g, k
                    n_amb += 1
    return n_amb


@njit(cache=True)
def _scene_by_loop(
    padding, s_inner, s_radius, c_start, c_radius, g_joint, g_radius, g_clusters, world, gworld, cworld, placement,
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact, amb,
):  # fmt: skip
    """Robot-vs-scene part of :func:`classify_state` without a grid (a small scene): every obstacle against every
    moving group, through the group's and its clusters' bounds. Returns like :func:`_scene_by_grid`.

    The group and cluster tests are written out here and in :func:`_scene_by_grid`: as helpers called per
    (obstacle, group) with twenty array arguments they made a state 3 to 6 times slower on MotionBenchMaker
    scenes (numba keeps the calls).
    """
    n_amb = 0
    for k in range(box_c.shape[0] + sph_c.shape[0] + cyl_c.shape[0]):
        for g in range(g_joint.shape[0]):
            if g_joint[g] == 0:  # fixed to the world: like the exact checker, never tested against the scene
                continue
            gd = point_obstacle_distance(gworld[g], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r)
            if gd >= g_radius[g] + padding:
                continue
            touched = False
            for c in range(g_clusters[g], g_clusters[g + 1]):
                cd = point_obstacle_distance(cworld[c], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                             cyl_r)  # fmt: skip
                if cd >= c_radius[c] + padding:
                    continue
                _place_spheres(c, c_start, placement, world)
                for s in range(c_start[c], c_start[c + 1]):
                    d = point_obstacle_distance(world[s], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                                cyl_r)  # fmt: skip
                    if exact[k] and d < s_inner[s] + padding:
                        return -1
                    if d < s_radius[s] + padding:
                        touched = True
            if touched and n_amb < amb.shape[0]:
                amb[n_amb, 0], amb[n_amb, 1], amb[n_amb, 2] = 0, g, k
                n_amb += 1
    return n_amb


@njit(cache=True)
def classify_state(
    q, parent, kind, axis, prot, ppos, idx_q,
    s_joint, s_center, s_radius, s_inner, g_start, g_joint, g_center, g_radius, self_pairs, padding,
    c_start, c_joint, c_center, c_radius, g_clusters,
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact, grid_i, grid_f,
    rot, pos, world, gworld, cworld, placed, amb, mark,
):  # fmt: skip
    """VALID, COLLIDING or AMBIGUOUS for one configuration, and the number of ambiguous pairs.

    With a grid (:func:`~.grid.build_grid`) each moving cluster of spheres meets the obstacles listed in the cells
    its bounding sphere overlaps (:func:`_scene_by_grid`); without, each moving group meets every obstacle.
    A cluster's spheres are placed (in ``world``) only once its bound reaches an obstacle or a cluster of
    the other group of a self-collision pair, at most once per state (``placed``: a flag per cluster).

    COLLIDING: an *inner* ball (contained in the link) is within ``padding`` of an obstacle (whose primitive
    is ``exact``, not just a bound) or of an
    inner ball of a self-collision pair, so the exact model collides too. VALID: no *outer* (covering)
    sphere is. Otherwise the (kind, a, b) pairs whose outer spheres touch are written to ``amb``
    (kind 0: group a vs obstacle b; kind 1: group a vs group b) for the exact model to decide.
    """
    joint_poses_nb(q, parent, kind, axis, prot, ppos, idx_q, rot, pos)
    sphere_centers_nb(rot, pos, g_joint, g_center, gworld)
    sphere_centers_nb(rot, pos, c_joint, c_center, cworld)
    placed[:] = False
    placement = (s_joint, s_center, rot, pos, placed)
    if grid_i[0] > 0:
        n_amb = _scene_by_grid(
            padding, s_inner, s_radius, c_start, c_radius, g_joint, g_clusters, world, cworld, placement,
            box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact, grid_i, grid_f, amb, mark,
        )  # fmt: skip
    else:
        n_amb = _scene_by_loop(
            padding, s_inner, s_radius, c_start, c_radius, g_joint, g_radius, g_clusters, world, gworld, cworld,
            placement, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact, amb,
        )  # fmt: skip
    if n_amb < 0:
        return COLLIDING, 0
    for p in range(self_pairs.shape[0]):
        ga, gb = self_pairs[p, 0], self_pairs[p, 1]
        if _dist(gworld[ga], gworld[gb]) >= g_radius[ga] + g_radius[gb] + padding:
            continue
        touched = False
        for ca in range(g_clusters[ga], g_clusters[ga + 1]):
            if _dist(cworld[ca], gworld[gb]) >= c_radius[ca] + g_radius[gb] + padding:
                continue
            for cb in range(g_clusters[gb], g_clusters[gb + 1]):
                if _dist(cworld[ca], cworld[cb]) >= c_radius[ca] + c_radius[cb] + padding:
                    continue
                _place_spheres(ca, c_start, placement, world)
                _place_spheres(cb, c_start, placement, world)
                for sa in range(c_start[ca], c_start[ca + 1]):
                    if _dist(world[sa], cworld[cb]) >= s_radius[sa] + c_radius[cb] + padding:
                        continue
                    for sb in range(c_start[cb], c_start[cb + 1]):
                        d = _dist(world[sa], world[sb])
                        if d < s_inner[sa] + s_inner[sb] + padding:
                            return COLLIDING, 0
                        if d < s_radius[sa] + s_radius[sb] + padding:
                            touched = True
        if touched and n_amb < amb.shape[0]:
            amb[n_amb, 0], amb[n_amb, 1], amb[n_amb, 2] = 1, ga, gb
            n_amb += 1
    if n_amb > 0:
        return AMBIGUOUS, n_amb
    return VALID, 0


@njit(cache=True)
def scan_nb(Q, start, ri, rf, sf, grid_i, grid_f, amb, mark, stop_at_ambiguous):
    """First row >= ``start`` of ``Q`` that is not VALID: (row, status, n_ambiguous), or (-1, VALID, 0).

    ``ri``/``rf``/``sf``: :func:`~.packing.pack_robot` and :func:`~.packing.pack_scene` arrays;
    ``grid_i``/``grid_f``: :func:`~.grid.build_grid`'s; ``mark``: (2, n_obs + 1) int64 kept across calls. With
    ``stop_at_ambiguous`` false, AMBIGUOUS rows are reported as COLLIDING (the pure sphere model).
    """
    (parent, kind, axis, prot, ppos, idx_q, s_joint, s_center, s_radius, s_inner, g_start, g_joint, g_center, g_radius,
     self_pairs, padding, c_start, c_joint, c_center, c_radius, g_clusters) = unpack_robot(ri, rf)  # fmt: skip
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact = unpack_scene(sf)
    nj = parent.shape[0]
    rot = np.empty((nj, 3, 3))
    pos = np.empty((nj, 3))
    world = np.empty((s_joint.shape[0], 3))
    gworld = np.empty((g_joint.shape[0], 3))
    cworld = np.empty((c_joint.shape[0], 3))
    placed = np.empty(c_joint.shape[0], dtype=np.bool_)
    for i in range(start, Q.shape[0]):
        status, n_amb = classify_state(
            Q[i], parent, kind, axis, prot, ppos, idx_q,
            s_joint, s_center, s_radius, s_inner, g_start, g_joint, g_center, g_radius, self_pairs, padding,
            c_start, c_joint, c_center, c_radius, g_clusters,
            box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact, grid_i, grid_f,
            rot, pos, world, gworld, cworld, placed, amb, mark,
        )  # fmt: skip
        if status == COLLIDING:
            return i, COLLIDING, 0
        if status == AMBIGUOUS:
            return i, (AMBIGUOUS if stop_at_ambiguous else COLLIDING), n_amb
    return -1, VALID, 0


@njit(cache=True)
def sphere_obstacle_distances_nb(world, sf):
    """Signed distance from every point of ``world`` (n, 3) to every obstacle of ``sf``: (n, n_obstacles)."""
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, _ = unpack_scene(sf)
    n_obs = box_c.shape[0] + sph_c.shape[0] + cyl_c.shape[0]
    out = np.empty((world.shape[0], n_obs))
    for s in range(world.shape[0]):
        for k in range(n_obs):
            out[s, k] = point_obstacle_distance(world[s], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                                                cyl_r)  # fmt: skip
    return out
