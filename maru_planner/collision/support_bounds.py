"""Separating-axis lower bounds of a robot hull's distance to an obstacle primitive, the axis found by GJK.

For convex sets ``A`` and ``B`` and any unit direction ``m``, every ``a`` in ``A`` and ``b`` in ``B`` have
``|a - b| >= m·(a - b)``, so ``dist(A, B) >= min over A of m·a - max over B of m·b``: a lower bound from the two
support functions alone, whichever ``m`` is taken. The bound is tight for the direction between the closest points,
which GJK (Gilbert–Johnson–Keerthi) finds on the Minkowski difference ``A - B`` in a few iterations; GJK's own
arithmetic only chooses ``m``, so the bound stays sound where it converges poorly (it is then just lower).

``A`` is a robot geometry's convex hull (its vertices: the support function is exact over the hull, which contains
the mesh); ``B`` an obstacle's sphere-kernel primitive (box, sphere or cylinder; it contains the obstacle, so the
bound holds for the obstacle too). Certification (``certify.py``) takes this bound where the sphere cover leaves a
row without slack, before asking coal for the hull distance (~1 µs here against ~5 µs through Python).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

GJK_ITERATIONS = 12  # GJK steps at most (a polytope against a primitive converges in ~3-6)
GJK_TOLERANCE = 1e-6  # m: stop once the bound is this close to the distance of GJK's current point, plus:
GJK_RELATIVE_TOLERANCE = 1e-3  # of that distance (curved primitives converge slowly; a row needs no finer bound)


@njit(cache=True, inline="always")
def _hull_support(rot, pos, verts, start, end, dx, dy, dz, out):
    """The hull vertex (world) farthest along (dx, dy, dz), written to ``out``; its projection returned.
    ``verts`` are in the frame placed by ``rot``/``pos``: the direction is turned into it once."""
    lx = rot[0, 0] * dx + rot[1, 0] * dy + rot[2, 0] * dz
    ly = rot[0, 1] * dx + rot[1, 1] * dy + rot[2, 1] * dz
    lz = rot[0, 2] * dx + rot[1, 2] * dy + rot[2, 2] * dz
    best, arg = -math.inf, start
    for v in range(start, end):
        value = verts[v, 0] * lx + verts[v, 1] * ly + verts[v, 2] * lz
        if value > best:
            best, arg = value, v
    for i in range(3):
        out[i] = rot[i, 0] * verts[arg, 0] + rot[i, 1] * verts[arg, 1] + rot[i, 2] * verts[arg, 2] + pos[i]
    return best + pos[0] * dx + pos[1] * dy + pos[2] * dz


@njit(cache=True, inline="always")
def _primitive_low(k, dx, dy, dz, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, out):
    """The point of primitive ``k`` (kernel order: boxes, spheres, cylinders) least along (dx, dy, dz), a unit
    direction, written to ``out``; its projection returned."""
    nb, ns = box_c.shape[0], sph_c.shape[0]
    if k < nb:
        for i in range(3):
            out[i] = box_c[k, i]
        for a in range(3):
            along = box_r[k, 0, a] * dx + box_r[k, 1, a] * dy + box_r[k, 2, a] * dz
            sign = -1.0 if along > 0.0 else 1.0
            for i in range(3):
                out[i] += sign * box_h[k, a] * box_r[k, i, a]
    elif k - nb < ns:
        k -= nb
        out[0], out[1], out[2] = sph_c[k, 0] - sph_r[k] * dx, sph_c[k, 1] - sph_r[k] * dy, sph_c[k, 2] - sph_r[k] * dz
    else:
        k -= nb + ns
        ax, ay, az = cyl_a[k, 0], cyl_a[k, 1], cyl_a[k, 2]
        along = ax * dx + ay * dy + az * dz
        sign = -1.0 if along > 0.0 else 1.0
        rx, ry, rz = dx - along * ax, dy - along * ay, dz - along * az
        radial = math.sqrt(rx * rx + ry * ry + rz * rz)
        scale = cyl_r[k] / radial if radial > 1e-12 else 0.0
        out[0] = cyl_c[k, 0] + sign * cyl_h[k] * ax - scale * rx
        out[1] = cyl_c[k, 1] + sign * cyl_h[k] * ay - scale * ry
        out[2] = cyl_c[k, 2] + sign * cyl_h[k] * az - scale * rz
    return out[0] * dx + out[1] * dy + out[2] * dz


@njit(cache=True, inline="always")
def _primitive_closest(k, px, py, pz, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, out):
    """The point of primitive ``k`` nearest (px, py, pz) (the point itself where it is inside), into ``out``."""
    nb, ns = box_c.shape[0], sph_c.shape[0]
    if k < nb:
        dx, dy, dz = px - box_c[k, 0], py - box_c[k, 1], pz - box_c[k, 2]
        for i in range(3):
            out[i] = box_c[k, i]
        for a in range(3):
            local = box_r[k, 0, a] * dx + box_r[k, 1, a] * dy + box_r[k, 2, a] * dz
            local = min(max(local, -box_h[k, a]), box_h[k, a])
            for i in range(3):
                out[i] += local * box_r[k, i, a]
    elif k - nb < ns:
        k -= nb
        dx, dy, dz = px - sph_c[k, 0], py - sph_c[k, 1], pz - sph_c[k, 2]
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        scale = min(1.0, sph_r[k] / norm) if norm > 0.0 else 0.0
        out[0], out[1], out[2] = sph_c[k, 0] + scale * dx, sph_c[k, 1] + scale * dy, sph_c[k, 2] + scale * dz
    else:
        k -= nb + ns
        dx, dy, dz = px - cyl_c[k, 0], py - cyl_c[k, 1], pz - cyl_c[k, 2]
        ax, ay, az = cyl_a[k, 0], cyl_a[k, 1], cyl_a[k, 2]
        along = dx * ax + dy * ay + dz * az
        rx, ry, rz = dx - along * ax, dy - along * ay, dz - along * az
        radial = math.sqrt(rx * rx + ry * ry + rz * rz)
        scale = min(1.0, cyl_r[k] / radial) if radial > 0.0 else 0.0
        along = min(max(along, -cyl_h[k]), cyl_h[k])
        out[0] = cyl_c[k, 0] + along * ax + scale * rx
        out[1] = cyl_c[k, 1] + along * ay + scale * ry
        out[2] = cyl_c[k, 2] + along * az + scale * rz


@njit(cache=True)
def _closest_on_simplex(simplex, count, point, keep, idx, g, rhs, mu):
    """The point of the convex hull of ``simplex[:count]`` (≤ 4 points) nearest the origin among the faces holding
    the last point (GJK's newest support point), written to ``point``, and in ``keep`` which points it needs; brute
    force over those faces' affine projections (a face whose projection has a negative weight is not the answer).
    Returns the number kept (4: the origin is inside). ``idx``, ``g``, ``rhs``, ``mu``: work arrays."""
    newest = 1 << (count - 1)
    best, best_mask = math.inf, newest
    for mask in range(newest, 1 << count):  # GJK: the nearest face holds the newest support point
        m = 0
        for i in range(count):
            if mask & (1 << i):
                idx[m] = i
                m += 1
        # min |w0 + sum mu_i (w_i - w0)|: normal equations g mu = rhs
        for i in range(1, m):
            for j in range(1, m):
                g[i - 1, j - 1] = _edge_dot(simplex, idx[i], idx[0], idx[j], idx[0])
            rhs[i - 1] = -_edge_origin_dot(simplex, idx[i], idx[0], idx[0])
        if not _solve_small(g, rhs, m - 1, mu):
            continue
        lam0 = 1.0
        feasible = True
        for i in range(m - 1):
            lam0 -= mu[i]
            feasible = feasible and mu[i] >= 0.0
        if not feasible or lam0 < 0.0:
            continue
        px, py, pz = simplex[idx[0], 0], simplex[idx[0], 1], simplex[idx[0], 2]
        for i in range(1, m):
            px += mu[i - 1] * (simplex[idx[i], 0] - simplex[idx[0], 0])
            py += mu[i - 1] * (simplex[idx[i], 1] - simplex[idx[0], 1])
            pz += mu[i - 1] * (simplex[idx[i], 2] - simplex[idx[0], 2])
        norm = px * px + py * py + pz * pz
        if norm < best:
            best, best_mask = norm, mask
            point[0], point[1], point[2] = px, py, pz
    kept = 0
    for i in range(count):
        if best_mask & (1 << i):
            keep[kept] = i
            kept += 1
    return kept


@njit(cache=True, inline="always")
def _solve_small(g, rhs, n, out):
    """``g[:n, :n] x = rhs[:n]`` for n ≤ 3 by Cramer's rule into ``out``; False where ``g`` is (nearly) singular."""
    if n == 0:
        return True
    if n == 1:
        if abs(g[0, 0]) < 1e-18:
            return False
        out[0] = rhs[0] / g[0, 0]
        return True
    if n == 2:
        det = g[0, 0] * g[1, 1] - g[0, 1] * g[1, 0]
        if abs(det) < 1e-24:
            return False
        out[0] = (rhs[0] * g[1, 1] - g[0, 1] * rhs[1]) / det
        out[1] = (g[0, 0] * rhs[1] - rhs[0] * g[1, 0]) / det
        return True
    det = _det3(g[0, 0], g[0, 1], g[0, 2], g[1, 0], g[1, 1], g[1, 2], g[2, 0], g[2, 1], g[2, 2])
    if abs(det) < 1e-30:
        return False
    out[0] = _det3(rhs[0], g[0, 1], g[0, 2], rhs[1], g[1, 1], g[1, 2], rhs[2], g[2, 1], g[2, 2]) / det
    out[1] = _det3(g[0, 0], rhs[0], g[0, 2], g[1, 0], rhs[1], g[1, 2], g[2, 0], rhs[2], g[2, 2]) / det
    out[2] = _det3(g[0, 0], g[0, 1], rhs[0], g[1, 0], g[1, 1], rhs[1], g[2, 0], g[2, 1], rhs[2]) / det
    return True


@njit(cache=True, inline="always")
def _edge_dot(s, a, b, c, d):
    """(s[a] - s[b]) · (s[c] - s[d])."""
    return ((s[a, 0] - s[b, 0]) * (s[c, 0] - s[d, 0]) + (s[a, 1] - s[b, 1]) * (s[c, 1] - s[d, 1])
            + (s[a, 2] - s[b, 2]) * (s[c, 2] - s[d, 2]))  # fmt: skip


@njit(cache=True, inline="always")
def _edge_origin_dot(s, a, b, c):
    """(s[a] - s[b]) · s[c]."""
    return (s[a, 0] - s[b, 0]) * s[c, 0] + (s[a, 1] - s[b, 1]) * s[c, 1] + (s[a, 2] - s[b, 2]) * s[c, 2]


@njit(cache=True, inline="always")
def _det3(a, b, c, d, e, f, g, h, i):
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


@njit(cache=True)
def hull_primitive_bound(rot, pos, verts, start, end, k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h,
                         cyl_r, enough, near):  # fmt: skip
    """A lower bound of the distance between the hull ``verts[start:end]`` (placed by ``rot``/``pos``) and primitive
    ``k`` (module doc): the best separating-axis bound along GJK's directions; <= 0 where they may touch. Stops early
    once the bound reaches ``enough``. GJK starts from ``near`` (a point of the hull's body, e.g. its bounding
    sphere's centre) against the primitive's point nearest it: a first direction close to the answer."""
    simplex = np.empty((4, 3))
    a, b, v = np.empty(3), np.empty(3), np.empty(3)
    keep, idx = np.empty(4, dtype=np.int64), np.empty(4, dtype=np.int64)
    g, rhs, mu = np.empty((3, 3)), np.empty(3), np.empty(3)
    _primitive_closest(k, near[0], near[1], near[2], box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, b)
    for i in range(3):
        v[i] = near[i] - b[i]
    count, bound = 0, -math.inf
    for _ in range(GJK_ITERATIONS):
        norm = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        if norm < 1e-12:
            return min(bound, 0.0) if bound > -math.inf else 0.0
        dx, dy, dz = -v[0] / norm, -v[1] / norm, -v[2] / norm  # from A - B's point towards the origin
        # support of A - B along -v: A's farthest along -v minus B's least along -v
        high_a = _hull_support(rot, pos, verts, start, end, dx, dy, dz, a)
        low_b = _primitive_low(k, dx, dy, dz, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, b)
        # unit m = v / |v|: dist >= min_A m·a - max_B m·b = -(high_a - low_b)
        bound = max(bound, low_b - high_a)
        if bound >= enough or norm - bound <= GJK_TOLERANCE + GJK_RELATIVE_TOLERANCE * norm:
            return bound
        for i in range(3):  # the support point of A - B joins the simplex
            simplex[count, i] = a[i] - b[i]
        count += 1
        kept = _closest_on_simplex(simplex, count, v, keep, idx, g, rhs, mu)
        for j in range(kept):
            for i in range(3):
                simplex[j, i] = simplex[keep[j], i]
        count = kept
        if count == 4:  # the origin is inside: they may touch
            return min(bound, 0.0)
    return bound
