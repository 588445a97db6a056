"""One full configuration on the sphere model, in a tight loop down the sphere checker's bounding hierarchy (numba).

:func:`classify` computes forward kinematics once, then tests the robot's spheres against the scene primitives and
the SRDF's self-collision pairs down the hierarchy (group, cluster, sphere), a sphere placed only where its cluster's
bound reaches something; it answers exactly as the sphere checker's ``classify_state`` does without a grid
(:mod:`.sphere_scan`). States the spheres leave in doubt (outer spheres touch, no inner ball does) may be decided on
the exact shapes by GJK's bound (:func:`clear_on_shapes`, :mod:`.support_bounds`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.kernels.fk import joint_poses_nb, place_members, place_points, row_distance
from maru_planner.collision.kernels.primitives import AMBIGUOUS, COLLIDING, VALID, obstacle_bounds, obstacle_distance
from maru_planner.collision.kernels.support_bounds import (
    NO_SHAPE,
    convex_bound,
    load_primitive,
    new_records,
    place_shape,
)

CLEAR_BY = 1e-9  # m: GJK stops once a pair's bound is this far past the padding (clear_on_shapes)


@njit(cache=True)
def work_arrays(robot, scene):
    """:func:`classify`'s work arrays for unpack_robot/unpack_scene tuples: joint rotations and positions, world
    centres of the groups', clusters' and spheres' bounds, which groups' clusters and which clusters' spheres
    are placed (all rewritten per state), and the scene's :func:`~.primitives.obstacle_bounds`."""
    nj, ns, ng, nc = robot[0].shape[0], robot[6].shape[0], robot[11].shape[0], robot[17].shape[0]
    return (np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((ng, 3)), np.empty((nc, 3)), np.empty((ns, 3)),
            np.zeros(ng, dtype=np.bool_), np.zeros(nc, dtype=np.bool_), obstacle_bounds(scene))  # fmt: skip


@njit(cache=True, inline="always")
def _box_gap(bounds, k, lo0, lo1, lo2, hi0, hi1, hi2):
    """How far the box ``[lo, hi]`` lies outside obstacle ``k``'s axis-aligned bounds along the axis where it lies
    farthest (<= 0: they overlap). One comparison of the largest excess, not six short-circuited ones: their
    branches mispredict."""
    return max(max(bounds[k, 0] - hi0, lo0 - bounds[k, 3]), max(bounds[k, 1] - hi1, lo1 - bounds[k, 4]),
               max(bounds[k, 2] - hi2, lo2 - bounds[k, 5]))  # fmt: skip


@njit(cache=True, inline="always")
def _beyond(world, i, reach, bounds, k):
    """Whether ``world[i]`` is at least ``reach`` outside obstacle ``k``'s axis-aligned bounds along some axis
    (then it is that far from the obstacle: a test without the obstacle's rotation or a square root)."""
    x, y, z = world[i, 0], world[i, 1], world[i, 2]
    return _box_gap(bounds, k, x, y, z, x, y, z) >= reach


@njit(cache=True, inline="always")
def _to_obstacle(world, i, k, scene):
    """Signed distance from ``world[i]`` to obstacle ``k`` of an unpack_scene tuple."""
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, _ = scene
    return obstacle_distance(world[i, 0], world[i, 1], world[i, 2], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c,
                             cyl_a, cyl_h, cyl_r)  # fmt: skip


@njit(cache=True, inline="always")
def _group_vs_obstacle(g, k, robot, scene, work, stop_at_touch):
    """Group ``g`` against obstacle ``k``, whose bounds meet: 0 its outer spheres clear the obstacle, 1 some touch
    it, 2 an inner ball hits it and it is exact (or, with ``stop_at_touch``, an outer sphere touches it: the answer
    is then decided)."""
    (_, _, _, _, _, _, s_joint, s_center, s_radius, s_inner, _, _, _, _, _, padding,
     c_start, c_joint, c_center, c_radius, g_clusters) = robot  # fmt: skip
    rot, pos, _, cworld, sworld, clusters_placed, spheres_placed, bounds = work
    exact = scene[9]
    place_members(g, g_clusters, clusters_placed, rot, pos, c_joint, c_center, cworld)
    touched = 0
    for c in range(g_clusters[g], g_clusters[g + 1]):
        reach = c_radius[c] + padding
        if _beyond(cworld, c, reach, bounds, k) or _to_obstacle(cworld, c, k, scene) >= reach:
            continue
        place_members(c, c_start, spheres_placed, rot, pos, s_joint, s_center, sworld)
        for s in range(c_start[c], c_start[c + 1]):
            d = _to_obstacle(sworld, s, k, scene)
            if (exact[k] and d < s_inner[s] + padding) or (stop_at_touch and d < s_radius[s] + padding):
                return 2
            if d < s_radius[s] + padding:
                touched = 1
    return touched


@njit(cache=True, inline="always")
def _pair_vs_pair(ga, gb, robot, work, stop_at_touch):
    """Self-collision pair (ga, gb), whose groups' bounds meet, as _group_vs_obstacle answers: 0 clear, 1 outer
    spheres touch, 2 inner balls hit (or outer spheres touch, with ``stop_at_touch``)."""
    (_, _, _, _, _, _, s_joint, s_center, s_radius, s_inner, _, _, _, g_radius, _, padding,
     c_start, c_joint, c_center, c_radius, g_clusters) = robot  # fmt: skip
    rot, pos, gworld, cworld, sworld, clusters_placed, spheres_placed, _ = work
    place_members(ga, g_clusters, clusters_placed, rot, pos, c_joint, c_center, cworld)
    place_members(gb, g_clusters, clusters_placed, rot, pos, c_joint, c_center, cworld)
    touched = 0
    for ca in range(g_clusters[ga], g_clusters[ga + 1]):
        if row_distance(cworld, ca, gworld, gb) >= c_radius[ca] + g_radius[gb] + padding:
            continue
        for cb in range(g_clusters[gb], g_clusters[gb + 1]):
            if row_distance(cworld, ca, cworld, cb) >= c_radius[ca] + c_radius[cb] + padding:
                continue
            place_members(ca, c_start, spheres_placed, rot, pos, s_joint, s_center, sworld)
            place_members(cb, c_start, spheres_placed, rot, pos, s_joint, s_center, sworld)
            for sa in range(c_start[ca], c_start[ca + 1]):
                if row_distance(sworld, sa, cworld, cb) >= s_radius[sa] + c_radius[cb] + padding:
                    continue
                for sb in range(c_start[cb], c_start[cb + 1]):
                    d = row_distance(sworld, sa, sworld, sb)
                    if d < s_inner[sa] + s_inner[sb] + padding or (
                        stop_at_touch and d < s_radius[sa] + s_radius[sb] + padding
                    ):
                        return 2
                    if d < s_radius[sa] + s_radius[sb] + padding:
                        touched = 1
    return touched


@njit(cache=True, inline="always")
def _vs_scene(robot, scene, work, stop_at_touch):
    """Every moving group against every obstacle, answered like :func:`_group_vs_obstacle`.

    The groups' bound test stays in this loop: inside the inlined helper, numba's reference counting of the
    helper's array arguments made every (group, obstacle) test cost as much as the spheres'.
    """
    g_joint, g_radius, padding = robot[11], robot[13], robot[15]  # unpack_robot's order
    gworld, bounds = work[2], work[7]
    lo0 = lo1 = lo2 = np.inf  # the moving groups' bounds, padded: an obstacle beyond this box is beyond all of them
    hi0 = hi1 = hi2 = -np.inf
    for g in range(g_joint.shape[0]):
        if g_joint[g] != 0:
            reach = g_radius[g] + padding
            lo0, hi0 = min(lo0, gworld[g, 0] - reach), max(hi0, gworld[g, 0] + reach)
            lo1, hi1 = min(lo1, gworld[g, 1] - reach), max(hi1, gworld[g, 1] + reach)
            lo2, hi2 = min(lo2, gworld[g, 2] - reach), max(hi2, gworld[g, 2] + reach)
    touched = 0
    for k in range(bounds.shape[0]):
        if _box_gap(bounds, k, lo0, lo1, lo2, hi0, hi1, hi2) >= 0.0:
            continue
        for g in range(g_joint.shape[0]):
            if g_joint[g] == 0:  # fixed to the world: like the exact checker, never tested against the scene
                continue
            reach = g_radius[g] + padding
            if _beyond(gworld, g, reach, bounds, k) or _to_obstacle(gworld, g, k, scene) >= reach:
                continue
            hit = _group_vs_obstacle(g, k, robot, scene, work, stop_at_touch)
            if hit == 2:
                return 2
            touched |= hit
    return touched


@njit(cache=True, inline="always")
def _vs_self(robot, work, stop_at_touch):
    """Every self-collision pair, answered like :func:`_pair_vs_pair` (its groups' bound test here, as in
    :func:`_vs_scene`)."""
    g_radius, self_pairs, padding = robot[13], robot[14], robot[15]
    gworld = work[2]
    touched = 0
    for p in range(self_pairs.shape[0]):
        ga, gb = self_pairs[p, 0], self_pairs[p, 1]
        if row_distance(gworld, ga, gworld, gb) >= g_radius[ga] + g_radius[gb] + padding:
            continue
        hit = _pair_vs_pair(ga, gb, robot, work, stop_at_touch)
        if hit == 2:
            return 2
        touched |= hit
    return touched


@njit(cache=True, inline="always")
def _place_state(q, robot, work):
    """``work``'s joint poses and group centres for full configuration ``q``, no cluster or sphere placed yet."""
    parent, kind, axis, prot, ppos, idx_q = robot[:6]
    rot, pos, gworld, _, _, clusters_placed, spheres_placed, _ = work
    joint_poses_nb(q, parent, kind, axis, prot, ppos, idx_q, rot, pos)
    place_points(rot, pos, robot[11], robot[12], 0, robot[11].shape[0], gworld)
    clusters_placed[:] = False
    spheres_placed[:] = False


@njit(cache=True, inline="always")
def classify(q, robot, scene, work, stop_at_touch):
    """VALID, COLLIDING or AMBIGUOUS for one full configuration: the answer of the sphere checker's
    classify_state without a grid, computed in a tight loop down the bounding hierarchy. Every group's
    bound is placed once; a group's clusters only when its bound reaches an obstacle or the other group
    of a self-collision pair, a cluster's spheres only when its bound does, each at most once per state.
    ``stop_at_touch``: AMBIGUOUS counts as COLLIDING (the pure sphere model), so the first outer sphere
    that touches ends the test.

    ``robot``/``scene``: unpack_robot/unpack_scene tuples; ``work``: :func:`work_arrays`. Inlined into its
    caller's loop: a call per state, with these tuples as arguments, cost about a third of a microsecond.
    """
    _place_state(q, robot, work)
    scene_hit = _vs_scene(robot, scene, work, stop_at_touch)
    if scene_hit == 2:
        return COLLIDING
    self_hit = _vs_self(robot, work, stop_at_touch)
    if self_hit == 2:
        return COLLIDING
    return AMBIGUOUS if scene_hit or self_hit else VALID


@njit(cache=True, inline="always")
def _apart_on_shapes(a, b, obstacle, robot, scene, work, shapes, records):
    """Whether GJK's lower bound (``support_bounds``) keeps group ``a``'s exact shape farther than the padding from
    obstacle ``b``'s primitive (which contains the obstacle) or, not ``obstacle``, from group ``b``'s shape, at the
    poses in ``work``; False without a shape (``shapes``: the robot's records; ``records``: two work records)."""
    g_joint, padding = robot[11], robot[15]
    rot, pos, gworld = work[0], work[1], work[2]
    s_kind, s_rot, s_pos, s_size, s_start, verts = shapes
    kinds, cs, rs, ss, vr = records
    if s_kind[a] == NO_SHAPE or (not obstacle and s_kind[b] == NO_SHAPE):
        return False
    place_shape(a, rot[g_joint[a]], pos[g_joint[a]], s_kind, s_rot, s_pos, s_size, s_start, 0, kinds, cs, rs, ss, vr)
    if obstacle:
        box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, _ = scene
        load_primitive(b, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, 1, kinds, cs, rs, ss)
    else:
        place_shape(b, rot[g_joint[b]], pos[g_joint[b]], s_kind, s_rot, s_pos, s_size, s_start, 1, kinds, cs, rs, ss,
                    vr)  # fmt: skip
    return convex_bound(kinds, cs, rs, ss, vr, verts, padding + CLEAR_BY, gworld[a]) > padding


@njit(cache=True)
def clear_on_shapes(q, robot, scene, work, shapes):
    """Whether every pair of full configuration ``q`` that the sphere model leaves in doubt (outer spheres within
    the padding, no inner ball hit) is :func:`_apart_on_shapes`: then coal would find no contact either (a mesh's
    hull contains it, an obstacle's primitive the obstacle). The pairs are found as :func:`classify` finds them;
    False at the first one not proven apart. Rewrites ``work`` for ``q``."""
    g_joint, g_radius, self_pairs, padding = robot[11], robot[13], robot[14], robot[15]
    _place_state(q, robot, work)
    gworld, records = work[2], new_records()
    n_obstacles = scene[0].shape[0] + scene[3].shape[0] + scene[5].shape[0]
    for g in range(g_joint.shape[0]):
        if g_joint[g] == 0:  # fixed to the world: never tested against the scene
            continue
        for k in range(n_obstacles):
            if _to_obstacle(gworld, g, k, scene) >= g_radius[g] + padding:
                continue
            touch = _group_vs_obstacle(g, k, robot, scene, work, False)
            if touch == 2 or (touch == 1 and not _apart_on_shapes(g, k, True, robot, scene, work, shapes, records)):
                return False
    for p in range(self_pairs.shape[0]):
        a, b = self_pairs[p, 0], self_pairs[p, 1]
        if row_distance(gworld, a, gworld, b) >= g_radius[a] + g_radius[b] + padding:
            continue
        touch = _pair_vs_pair(a, b, robot, work, False)
        if touch == 2 or (touch == 1 and not _apart_on_shapes(a, b, False, robot, scene, work, shapes, records)):
            return False
    return True


@njit(cache=True)
def pairs_clear_on_shapes(q, pairs, robot, scene, work, shapes):
    """:func:`clear_on_shapes` of the pairs a scan listed in doubt at ``q`` (``scan_nb``'s ``amb``: kind 0 a group
    and an obstacle, 1 two groups)."""
    _place_state(q, robot, work)
    records = new_records()
    for i in range(pairs.shape[0]):
        if not _apart_on_shapes(pairs[i, 1], pairs[i, 2], pairs[i, 0] == 0, robot, scene, work, shapes, records):
            return False
    return True
