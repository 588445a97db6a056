"""Separating-axis lower bounds of the distance between two convex shapes, the axis found by GJK.

For convex sets ``A`` and ``B`` and any unit direction ``m``, every ``a`` in ``A`` and ``b`` in ``B`` have
``|a - b| >= m·(a - b)``, so ``dist(A, B) >= min over A of m·a - max over B of m·b``: a lower bound from the two
support functions alone, whichever ``m`` is taken. The bound is tight for the direction between the closest points,
which GJK (Gilbert–Johnson–Keerthi) finds on the Minkowski difference ``A - B`` in a few iterations; GJK's own
arithmetic only chooses ``m``, so the bound stays sound where it converges poorly (it is then just lower).

A shape is a *record* in slot 0 (``A``) or 1 (``B``) of four small arrays: its kind (:data:`BOX`, :data:`SPHERE`,
:data:`CYLINDER`: the sphere kernels' primitives, or :data:`HULL`: the vertices ``verts[start:end]``, whose support
function is exact over the hull, which contains the mesh), its centre, its rotation (world from shape; a cylinder's
axis is its third column, a hull's vertices are in this frame) and its size (a box's half extents; a sphere's radius
first; a cylinder's radius first and half length last). A robot's records come from
:func:`maru_planner.collision.shape_records.robot_shape_records`. Certification (:mod:`maru_planner.collision.certify`)
takes this bound where the sphere cover leaves a row without slack, before asking coal (~1 µs here against ~5-10 µs
through Python): a robot hull against an obstacle's primitive, and primitives against primitives, where the bound is
the distance itself; the search kernels decide with it the states the spheres leave in doubt
(:mod:`.state_validity`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

GJK_ITERATIONS = 12  # GJK steps at most (a polytope against a primitive converges in ~3-6)
GJK_TOLERANCE = 1e-6  # m: stop once the bound is this close to the distance of GJK's current point, plus:
GJK_RELATIVE_TOLERANCE = 1e-3  # of that distance (curved primitives converge slowly; a row needs no finer bound)
NO_SHAPE, BOX, SPHERE, CYLINDER, HULL = -1, 0, 1, 2, 3  # record kinds (the first three: the kernels' order)


@njit(cache=True)
def new_records():
    """Two empty shape records (kinds, centres, rotations, sizes, vertex ranges), for :func:`convex_bound`."""
    return (np.full(2, NO_SHAPE, dtype=np.int64), np.zeros((2, 3)), np.zeros((2, 3, 3)), np.zeros((2, 3)),
            np.zeros((2, 2), dtype=np.int64))  # fmt: skip


@njit(cache=True, inline="always")
def load_primitive(k, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, slot, kinds, cs, rs, ss):
    """Primitive ``k`` of the kernels' arrays (boxes, spheres, cylinders) into record ``slot``."""
    nb, ns = box_c.shape[0], sph_c.shape[0]
    if k < nb:
        kinds[slot] = BOX
        for i in range(3):
            cs[slot, i], ss[slot, i] = box_c[k, i], box_h[k, i]
            for j in range(3):
                rs[slot, i, j] = box_r[k, i, j]
    elif k - nb < ns:
        k -= nb
        kinds[slot] = SPHERE
        for i in range(3):
            cs[slot, i] = sph_c[k, i]
        ss[slot, 0] = sph_r[k]
    else:
        k -= nb + ns
        kinds[slot] = CYLINDER
        for i in range(3):
            cs[slot, i], rs[slot, i, 2] = cyl_c[k, i], cyl_a[k, i]
        ss[slot, 0], ss[slot, 2] = cyl_r[k], cyl_h[k]


@njit(cache=True, inline="always")
def place_shape(g, rot, pos, g_kind, g_rot, g_pos, g_size, g_verts, slot, kinds, cs, rs, ss, vr):
    """Robot shape ``g`` (kind, placement in its joint's frame, size, vertex range) into record ``slot``, its joint
    at ``rot``/``pos``."""
    kinds[slot] = g_kind[g]
    for i in range(3):
        cs[slot, i] = pos[i] + rot[i, 0] * g_pos[g, 0] + rot[i, 1] * g_pos[g, 1] + rot[i, 2] * g_pos[g, 2]
        ss[slot, i] = g_size[g, i]
        for j in range(3):
            rs[slot, i, j] = rot[i, 0] * g_rot[g, 0, j] + rot[i, 1] * g_rot[g, 1, j] + rot[i, 2] * g_rot[g, 2, j]
    vr[slot, 0], vr[slot, 1] = g_verts[g], g_verts[g + 1]


@njit(cache=True, inline="always")
def _support(slot, kinds, cs, rs, ss, vr, verts, dx, dy, dz, out):
    """The point of record ``slot`` farthest along the unit direction (dx, dy, dz), written to ``out``; its
    projection returned."""
    kind = kinds[slot]
    if kind == SPHERE:
        r = ss[slot, 0]
        out[0], out[1], out[2] = cs[slot, 0] + r * dx, cs[slot, 1] + r * dy, cs[slot, 2] + r * dz
    elif kind == BOX:
        for i in range(3):
            out[i] = cs[slot, i]
        for a in range(3):
            along = rs[slot, 0, a] * dx + rs[slot, 1, a] * dy + rs[slot, 2, a] * dz
            sign = 1.0 if along > 0.0 else -1.0
            for i in range(3):
                out[i] += sign * ss[slot, a] * rs[slot, i, a]
    elif kind == CYLINDER:
        ax, ay, az = rs[slot, 0, 2], rs[slot, 1, 2], rs[slot, 2, 2]
        along = ax * dx + ay * dy + az * dz
        sign = 1.0 if along > 0.0 else -1.0
        rx, ry, rz = dx - along * ax, dy - along * ay, dz - along * az
        radial = math.sqrt(rx * rx + ry * ry + rz * rz)
        scale = ss[slot, 0] / radial if radial > 1e-12 else 0.0
        h = ss[slot, 2]
        out[0] = cs[slot, 0] + sign * h * ax + scale * rx
        out[1] = cs[slot, 1] + sign * h * ay + scale * ry
        out[2] = cs[slot, 2] + sign * h * az + scale * rz
    else:  # HULL: the direction turned into the vertices' frame once
        lx = rs[slot, 0, 0] * dx + rs[slot, 1, 0] * dy + rs[slot, 2, 0] * dz
        ly = rs[slot, 0, 1] * dx + rs[slot, 1, 1] * dy + rs[slot, 2, 1] * dz
        lz = rs[slot, 0, 2] * dx + rs[slot, 1, 2] * dy + rs[slot, 2, 2] * dz
        best, arg = -math.inf, vr[slot, 0]
        for v in range(vr[slot, 0], vr[slot, 1]):
            value = verts[v, 0] * lx + verts[v, 1] * ly + verts[v, 2] * lz
            if value > best:
                best, arg = value, v
        for i in range(3):
            out[i] = (rs[slot, i, 0] * verts[arg, 0] + rs[slot, i, 1] * verts[arg, 1] + rs[slot, i, 2] * verts[arg, 2]
                      + cs[slot, i])  # fmt: skip
    return out[0] * dx + out[1] * dy + out[2] * dz


@njit(cache=True, inline="always")
def _closest(slot, kinds, cs, rs, ss, px, py, pz, out):
    """The point of record ``slot`` nearest (px, py, pz) (the point itself where it is inside), into ``out``; a hull's
    frame origin stands for it (GJK only starts from it)."""
    kind = kinds[slot]
    dx, dy, dz = px - cs[slot, 0], py - cs[slot, 1], pz - cs[slot, 2]
    for i in range(3):
        out[i] = cs[slot, i]
    if kind == BOX:
        for a in range(3):
            local = rs[slot, 0, a] * dx + rs[slot, 1, a] * dy + rs[slot, 2, a] * dz
            local = min(max(local, -ss[slot, a]), ss[slot, a])
            for i in range(3):
                out[i] += local * rs[slot, i, a]
    elif kind == SPHERE:
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        scale = min(1.0, ss[slot, 0] / norm) if norm > 0.0 else 0.0
        out[0], out[1], out[2] = out[0] + scale * dx, out[1] + scale * dy, out[2] + scale * dz
    elif kind == CYLINDER:
        ax, ay, az = rs[slot, 0, 2], rs[slot, 1, 2], rs[slot, 2, 2]
        along = dx * ax + dy * ay + dz * az
        rx, ry, rz = dx - along * ax, dy - along * ay, dz - along * az
        radial = math.sqrt(rx * rx + ry * ry + rz * rz)
        scale = min(1.0, ss[slot, 0] / radial) if radial > 0.0 else 0.0
        along = min(max(along, -ss[slot, 2]), ss[slot, 2])
        out[0] += along * ax + scale * rx
        out[1] += along * ay + scale * ry
        out[2] += along * az + scale * rz


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
def convex_bound(kinds, cs, rs, ss, vr, verts, enough, near):
    """A lower bound of the distance between records 0 (``A``) and 1 (``B``) (module doc): the best separating-axis
    bound along GJK's directions; <= 0 where they may touch. Stops early once the bound reaches ``enough``. GJK starts
    from ``near`` (a point of ``A``'s body, e.g. its bounding sphere's centre) against ``B``'s point nearest it: a
    first direction close to the answer."""
    simplex = np.empty((4, 3))
    a, b, v = np.empty(3), np.empty(3), np.empty(3)
    keep, idx = np.empty(4, dtype=np.int64), np.empty(4, dtype=np.int64)
    g, rhs, mu = np.empty((3, 3)), np.empty(3), np.empty(3)
    _closest(1, kinds, cs, rs, ss, near[0], near[1], near[2], b)
    for i in range(3):
        v[i] = near[i] - b[i]
    count, bound = 0, -math.inf
    for _ in range(GJK_ITERATIONS):
        norm = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        if norm < 1e-12:
            return min(bound, 0.0) if bound > -math.inf else 0.0
        dx, dy, dz = -v[0] / norm, -v[1] / norm, -v[2] / norm  # from A - B's point towards the origin
        # support of A - B along -v: A's farthest along -v minus B's least along -v (its farthest along v)
        high_a = _support(0, kinds, cs, rs, ss, vr, verts, dx, dy, dz, a)
        low_b = -_support(1, kinds, cs, rs, ss, vr, verts, -dx, -dy, -dz, b)
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
