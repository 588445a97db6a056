"""The certification's row kernels (numba): per (segment, pair, piece) row at the middle of its piece, the pair's
distance bound (bounding volumes, the sphere cover, GJK on the shapes the kernels hold) and how fast that distance
can change along the segment (the levers, tightened at the middle's configuration)."""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.certify.cover import DISTANCE_TOLERANCE, cover_bounds_nb
from maru_planner.collision.kernels.fk import (
    joint_pose_nb,
    joint_poses_nb,
    point_in_world,
    root_pose_nb,
    row_distance,
    sphere_centers_nb,
)
from maru_planner.collision.kernels.support_bounds import convex_bound, load_primitive, new_records, place_shape

ROWS_FOR_ALL = 8  # rows per configuration from which a round poses every joint at once (place_rows_nb)
# what the row kernel's GJK bound (support_bounds) is for a pair: none (coal measures it), a lower bound (a robot
# hull: coal's mesh is finer), the distance itself (primitives on both sides, exactly the pair's shapes)
MEASURE_NONE, MEASURE_BOUND, MEASURE_EXACT = 0, 1, 2
COVER_SLACK_SPLIT = 16  # see proves_too_little (2 x the MAX_SPLIT of 8 it was chosen with)


@njit(cache=True)
def poses_nb(configs, parent, kind, axis, prot, ppos, idx_q, joint, local, rots, poss, centers):
    """Per configuration: every joint's world pose (``rots``, ``poss``) and the world centres of the geometries'
    bounding spheres."""
    for i in range(configs.shape[0]):
        joint_poses_nb(configs[i], parent, kind, axis, prot, ppos, idx_q, rots[i], poss[i])
        sphere_centers_nb(rots[i], poss[i], joint, local, centers[i])


@njit(cache=True)
def place_rows_nb(configs, config_of, pair, first, other, parent, kind, axis, prot, ppos, idx_q, joint, local, rots,
                   poss, centers, posed):  # fmt: skip
    """What each row uses at its configuration: the poses of the joints on the chains to its pair's geometries
    (``posed``) and their bounding-sphere centres. A later round's configuration serves a few rows, often on one
    arm: the other joints are left unposed (Maru-1 needs 43 % of its joint poses, the Panda 79 %). Configurations
    serving :data:`ROWS_FOR_ALL` rows each or more on average (a first round's: every pair) are posed whole."""
    if pair.shape[0] >= ROWS_FOR_ALL * configs.shape[0]:
        poses_nb(configs, parent, kind, axis, prot, ppos, idx_q, joint, local, rots, poss, centers)
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
def to_axis_nb(rot, pos, axis, q_joint, center, posed, out):
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
def volume_bounds_nb(centers, config_of, pair, first, second, obstacle, box_center, box_rot, box_half, radius, out):
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
def assess_rows_nb(configs, config_of, seg, pair, half, run_arrays, pair_arrays, robot_arrays, cover_arrays,
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
        pair_arrays)  # fmt: skip
    parent, kind, axis, prot, ppos, idx_q, g_joint, g_local, g_radius, q_joint, levers, prismatic = robot_arrays
    n_rows, n_geoms, nq, n_configs = seg.shape[0], g_joint.shape[0], q_joint.shape[0], configs.shape[0]
    rots, poss = np.empty((n_configs, parent.shape[0], 3, 3)), np.empty((n_configs, parent.shape[0], 3))
    centers = np.empty((n_configs, n_geoms, 3))
    posed = np.zeros((n_configs, parent.shape[0]), dtype=np.bool_)
    place_rows_nb(configs, config_of, pair, first, other, parent, kind, axis, prot, ppos, idx_q, g_joint, g_local,
                   rots, poss, centers, posed)  # fmt: skip
    volume = np.empty(n_rows)
    volume_bounds_nb(centers, config_of, pair, first, second, obstacle, box_center, box_rot, box_half, g_radius,
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
                    to_axis_nb(rots[c], poss[c], axis, q_joint, centers[c, b], posed[c], to_axis[c, b])
                    has_axis[c, b] = True
            for j in range(nq):
                lever = 0.0
                if moves_first[p, j]:
                    lever += 1.0 if prismatic[j] else min(
                        levers[g, j], to_axis[c, g, j] + g_radius[g] + half[r] * downstream[s, g, j])  # fmt: skip
                if moves_other[p, j]:
                    lever += 1.0 if prismatic[j] else min(
                        levers[o, j], to_axis[c, o, j] + g_radius[o] + half[r] * downstream[s, o, j])  # fmt: skip
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
            no_slack or thin or not covered[p])  # fmt: skip
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
