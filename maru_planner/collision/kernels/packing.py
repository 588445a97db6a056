"""The robot and the scene as the few flat arrays the kernels take (cheap numba dispatch), and unpacked again inside
them into named arrays.

``pack_robot``'s two arrays hold the kinematic tree (:mod:`.fk`), the robot's spheres (outer and inner radii, per
sphere its joint and centre), their clusters and groups (one group per collision geometry, with each group's and
cluster's bounding sphere) and the self-collision pairs; ``pack_scene``'s the obstacles' primitives
(:mod:`.primitives`) and whether each one is its obstacle exactly.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def pack_robot(parent, kind, axis, prot, ppos, idx_q, s_joint, s_center, s_radius, s_inner,
               g_start, g_joint, g_center, g_radius, self_pairs, padding,
               c_start, c_joint, c_center, c_radius, g_clusters):  # fmt: skip
    """Robot data as one int64 and one float64 array: few kernel arguments, cheap numba dispatch."""
    nj, ns, ng, npairs, nc = len(parent), len(s_joint), len(g_joint), len(self_pairs), len(c_joint)
    ints = np.concatenate([
        [nj, ns, ng, npairs, nc], parent, kind, idx_q, s_joint, g_start, g_joint, np.asarray(self_pairs).reshape(-1),
        c_start, c_joint, g_clusters,
    ]).astype(np.int64)  # fmt: skip
    floats = np.concatenate([
        [padding], np.ravel(axis), np.ravel(prot), np.ravel(ppos), np.ravel(s_center), s_radius, s_inner,
        np.ravel(g_center), g_radius, np.ravel(c_center), c_radius,
    ]).astype(np.float64)  # fmt: skip
    return ints, floats


def pack_scene(box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact):
    """Scene primitives as one float64 array (counts first; ``exact`` as 0/1)."""
    parts = [[len(box_c), len(sph_c), len(cyl_c)], box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r,
             exact]  # fmt: skip
    return np.concatenate([np.ravel(np.asarray(p, dtype=np.float64)) for p in parts])


@njit(cache=True)
def unpack_robot(ri, rf):
    nj, ns, ng, npairs, nc = ri[0], ri[1], ri[2], ri[3], ri[4]
    o = 5
    parent = ri[o : o + nj]
    kind = ri[o + nj : o + 2 * nj]
    idx_q = ri[o + 2 * nj : o + 3 * nj]
    o += 3 * nj
    s_joint = ri[o : o + ns]
    o += ns
    g_start = ri[o : o + ng + 1]
    o += ng + 1
    g_joint = ri[o : o + ng]
    o += ng
    self_pairs = ri[o : o + 2 * npairs].reshape((npairs, 2))
    o += 2 * npairs
    c_start = ri[o : o + nc + 1]
    o += nc + 1
    c_joint = ri[o : o + nc]
    o += nc
    g_clusters = ri[o : o + ng + 1]
    padding = rf[0]
    f = 1
    axis = rf[f : f + 3 * nj].reshape((nj, 3))
    f += 3 * nj
    prot = rf[f : f + 9 * nj].reshape((nj, 3, 3))
    f += 9 * nj
    ppos = rf[f : f + 3 * nj].reshape((nj, 3))
    f += 3 * nj
    s_center = rf[f : f + 3 * ns].reshape((ns, 3))
    f += 3 * ns
    s_radius = rf[f : f + ns]
    s_inner = rf[f + ns : f + 2 * ns]
    f += 2 * ns
    g_center = rf[f : f + 3 * ng].reshape((ng, 3))
    g_radius = rf[f + 3 * ng : f + 4 * ng]
    f += 4 * ng
    c_center = rf[f : f + 3 * nc].reshape((nc, 3))
    c_radius = rf[f + 3 * nc : f + 4 * nc]
    return (parent, kind, axis, prot, ppos, idx_q, s_joint, s_center, s_radius, s_inner, g_start, g_joint,
            g_center, g_radius, self_pairs, padding, c_start, c_joint, c_center, c_radius, g_clusters)  # fmt: skip


@njit(cache=True)
def unpack_scene(sf):
    nb, ns, nc = int(sf[0]), int(sf[1]), int(sf[2])
    o = 3
    box_c = sf[o : o + 3 * nb].reshape((nb, 3))
    o += 3 * nb
    box_r = sf[o : o + 9 * nb].reshape((nb, 3, 3))
    o += 9 * nb
    box_h = sf[o : o + 3 * nb].reshape((nb, 3))
    o += 3 * nb
    sph_c = sf[o : o + 3 * ns].reshape((ns, 3))
    o += 3 * ns
    sph_r = sf[o : o + ns]
    o += ns
    cyl_c = sf[o : o + 3 * nc].reshape((nc, 3))
    o += 3 * nc
    cyl_a = sf[o : o + 3 * nc].reshape((nc, 3))
    o += 3 * nc
    cyl_h = sf[o : o + nc]
    cyl_r = sf[o + nc : o + 2 * nc]
    o += 2 * nc
    exact = sf[o : o + nb + ns + nc] > 0.5
    return box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact
