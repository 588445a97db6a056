"""The scene's primitives in the kernels: signed distances to boxes, spheres and cylinders, their world bounds, and
the answers of every state test (numba).

All lengths in metres. Signed distances are negative inside. A robot sphere (centre c, radius r)
collides with a primitive when ``signed_distance(c, primitive) < r + padding``. Obstacle ``k`` of a scene is
its ``k``-th box, then sphere, then cylinder (:func:`maru_planner.collision.kernels.packing.unpack_scene`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

VALID, COLLIDING, AMBIGUOUS = 0, 1, 2  # a state's (or an edge's) answer on the sphere model


@njit(cache=True, inline="always")
def box_distance(px, py, pz, k, box_c, box_r, box_h):
    """Signed distance from a point to box ``k`` (world-from-box rotation ``box_r[k]``, half extents)."""
    dx, dy, dz = px - box_c[k, 0], py - box_c[k, 1], pz - box_c[k, 2]
    out2 = 0.0
    inside = 1e300
    for a in range(3):
        local = box_r[k, 0, a] * dx + box_r[k, 1, a] * dy + box_r[k, 2, a] * dz
        e = abs(local) - box_h[k, a]
        if e > 0.0:
            out2 += e * e
        if -e < inside:
            inside = -e
    if out2 > 0.0:
        return np.sqrt(out2)
    return -inside


@njit(cache=True, inline="always")
def cylinder_distance(px, py, pz, k, cyl_c, cyl_a, cyl_h, cyl_r):
    """Signed distance from a point to solid cylinder ``k`` (unit axis ``cyl_a[k]``, centred)."""
    dx, dy, dz = px - cyl_c[k, 0], py - cyl_c[k, 1], pz - cyl_c[k, 2]
    ax, ay, az = cyl_a[k, 0], cyl_a[k, 1], cyl_a[k, 2]
    t = dx * ax + dy * ay + dz * az
    rx, ry, rz = dx - t * ax, dy - t * ay, dz - t * az
    radial = np.sqrt(rx * rx + ry * ry + rz * rz)
    ez = abs(t) - cyl_h[k]
    er = radial - cyl_r[k]
    if ez > 0.0 or er > 0.0:
        ez = max(ez, 0.0)
        er = max(er, 0.0)
        return np.sqrt(ez * ez + er * er)
    return max(ez, er)


@njit(cache=True, inline="always")
def point_obstacle_distance(p, k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r):
    """Signed distance from ``p`` to obstacle ``k`` (boxes first, then spheres, then cylinders)."""
    return obstacle_distance(p[0], p[1], p[2], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r)


@njit(cache=True, inline="always")
def obstacle_distance(px, py, pz, k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r):
    """:func:`point_obstacle_distance` of the point (px, py, pz)."""
    nb, ns = box_c.shape[0], sph_c.shape[0]
    if k < nb:
        return box_distance(px, py, pz, k, box_c, box_r, box_h)
    k -= nb
    if k < ns:
        d0, d1, d2 = px - sph_c[k, 0], py - sph_c[k, 1], pz - sph_c[k, 2]
        return np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) - sph_r[k]
    return cylinder_distance(px, py, pz, k - ns, cyl_c, cyl_a, cyl_h, cyl_r)


@njit(cache=True)
def obstacle_bounds(scene):
    """World axis-aligned bounds (n, 6: lo, hi) of an unpack_scene tuple's obstacles, widened by a nanometre so
    that rounding never lets a point beyond them be nearer to the obstacle than it is to them."""
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact = scene
    nb, ns = box_c.shape[0], sph_c.shape[0]
    out = np.empty((exact.shape[0], 6))
    for k in range(exact.shape[0]):
        for a in range(3):
            if k < nb:
                c, h = box_c[k, a], 0.0
                for b in range(3):
                    h += abs(box_r[k, a, b]) * box_h[k, b]
            elif k < nb + ns:
                c, h = sph_c[k - nb, a], sph_r[k - nb]
            else:
                i = k - nb - ns
                c = cyl_c[i, a]
                h = abs(cyl_a[i, a]) * cyl_h[i] + np.sqrt(max(1.0 - cyl_a[i, a] ** 2, 0.0)) * cyl_r[i]
            out[k, a], out[k, 3 + a] = c - h - 1e-9, c + h + 1e-9
    return out
