"""Elastic-strip forces of paper 001, vectorised over via points and obstacle points.

- internal (contraction) force, eq. 36;
- external (repulsive) force from the nearest obstacle point, eq. 38-40 ("plain");
- modified external force, eq. 41-42: nearest point on the left plus nearest
  point on the right of the strip's local direction.

All functions take via points ``vias`` (k, 2) and obstacle points ``points``
(m, 2) in one frame and return forces (k, 2) in that frame. Work is O(k * m).
"""

from __future__ import annotations

import numpy as np

_EPS = 1e-9


def internal_forces(vias: np.ndarray, k_c: float) -> np.ndarray:
    """Eq. 36 on the inner vias: f_i = k_c (d_{i-1,i}/(d_{i-1,i}+d_{i,i+1}) (P_{i+1}-P_{i-1}) - (P_i-P_{i-1})).

    Straightens the strip while keeping the ratio of neighbouring spacings;
    the first and last via get zero force.
    """
    forces = np.zeros_like(vias, dtype=float)
    if len(vias) < 3:
        return forces
    prev, cur, nxt = vias[:-2], vias[1:-1], vias[2:]
    d_prev = np.linalg.norm(cur - prev, axis=1)
    d_next = np.linalg.norm(nxt - cur, axis=1)
    ratio = d_prev / np.maximum(d_prev + d_next, _EPS)
    forces[1:-1] = k_c * (ratio[:, None] * (nxt - prev) - (cur - prev))
    return forces


def repulsion(offset: np.ndarray, distance: np.ndarray, d0: float, k_r: float) -> np.ndarray:
    """Eq. 39: k_r (d0 - d) d/|d| for d < d0, else 0. ``offset`` = P_m - P_o (n, 2), ``distance`` = |offset|."""
    gain = k_r * np.clip(d0 - distance, 0.0, None) / np.maximum(distance, _EPS)
    gain[~np.isfinite(distance)] = 0.0
    return offset * gain[:, None]


def _offsets(vias: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    offsets = vias[:, None, :] - points[None, :, :]
    return offsets, np.hypot(offsets[..., 0], offsets[..., 1])


def _nearest(offsets: np.ndarray, dist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offset and distance to the nearest point per via (inf distance where the row is all inf)."""
    rows = np.arange(dist.shape[0])
    idx = np.argmin(dist, axis=1)
    return offsets[rows, idx], dist[rows, idx]


def plain_external_forces(vias: np.ndarray, points: np.ndarray, d0: float, k_r: float) -> np.ndarray:
    """Eq. 38-40: repulsion from the single nearest obstacle point of each via."""
    if len(points) == 0 or len(vias) == 0:
        return np.zeros((len(vias), 2))
    offsets, dist = _offsets(vias, points)
    offset, d = _nearest(offsets, dist)
    return repulsion(offset, d, d0, k_r)


def _side_split(vias: np.ndarray, tangents: np.ndarray, points: np.ndarray):
    offsets, dist = _offsets(vias, points)
    # cross(t, p - v) = -cross(t, v - p): >= 0 means the point is on the left (on the line counts as left)
    side = -(tangents[:, None, 0] * offsets[..., 1] - tangents[:, None, 1] * offsets[..., 0])
    return offsets, dist, side


def side_nearest(vias: np.ndarray, tangents: np.ndarray, points: np.ndarray):
    """Nearest obstacle point left and right of each via's direction ``tangents`` (unit, (k, 2)).

    Returns (offset_left, dist_left, offset_right, dist_right); a side with no
    point has distance inf. A point exactly on the line counts as left.
    """
    offsets, dist, side = _side_split(vias, tangents, points)
    left = side >= 0.0
    off_l, d_l = _nearest(offsets, np.where(left, dist, np.inf))
    off_r, d_r = _nearest(offsets, np.where(left, np.inf, dist))
    return off_l, d_l, off_r, d_r


def modified_external_forces(
    vias: np.ndarray,
    tangents: np.ndarray,
    points: np.ndarray,
    d0: float,
    k_r: float,
    head_on_ratio: float = 0.25,
    prefer: float | np.ndarray = 0.0,
    min_gap: float = 0.0,
) -> np.ndarray:
    """Eq. 41: ef(L) + ef(R), the repulsions of the nearest left and the nearest right obstacle point.

    Head-on case (our documented choice, see docs/reactive.md): when both
    sides push and their sum lies along the strip (its sideways part smaller
    than ``head_on_ratio`` of the along-strip part), the left and right
    points straddle the strip and their sideways pushes cancel - the
    situation where the plain form drives into the obstacle. The same holds
    when the two points are closer together (d_L + d_R) than ``min_gap`` (the
    robot's diameter): a slot too narrow to pass, where the two pushes also
    cancel and would centre the via in it. The via is then
    pushed sideways, with the magnitude of the stronger side force. The side:
    ``prefer`` when it is non-zero (per via; the strip passes the side a via
    has already moved to, so neighbouring vias do not split around an
    obstacle), else the side holding less obstacle within d0 (points weighted
    by d0 - d), else left. ``head_on_ratio=0`` disables the rule.
    """
    if len(points) == 0 or len(vias) == 0:
        return np.zeros((len(vias), 2))
    offsets, dist, side = _side_split(vias, tangents, points)
    left = side >= 0.0
    off_l, d_l = _nearest(offsets, np.where(left, dist, np.inf))
    off_r, d_r = _nearest(offsets, np.where(left, np.inf, dist))
    f_l = repulsion(off_l, d_l, d0, k_r)
    f_r = repulsion(off_r, d_r, d0, k_r)
    forces = f_l + f_r
    if head_on_ratio <= 0.0:
        return forces
    normals = np.stack([-tangents[:, 1], tangents[:, 0]], axis=1)
    axial = np.einsum("ij,ij->i", forces, tangents)
    lateral = np.einsum("ij,ij->i", forces, normals)
    mag_l = np.linalg.norm(f_l, axis=1)
    mag_r = np.linalg.norm(f_r, axis=1)
    both = (mag_l > 0) & (mag_r > 0)
    head_on = both & ((np.abs(lateral) < head_on_ratio * np.abs(axial)) | (d_l + d_r < min_gap))
    if np.any(head_on):
        weight = np.clip(d0 - dist[head_on], 0.0, None)
        # side > 0: point on the left; the signed lateral "mass" of obstacle within d0 of the via
        mass = np.sum(weight * np.sign(side[head_on]), axis=1)
        total = np.sum(weight, axis=1)
        by_mass = np.where(np.abs(mass) <= 0.1 * total, 1.0, -np.sign(mass))
        chosen = np.broadcast_to(np.asarray(prefer, dtype=float), (len(vias),))[head_on]
        sign = np.where(chosen != 0.0, np.sign(chosen), by_mass)
        push = np.maximum(mag_l, mag_r)[head_on]
        forces[head_on] += (sign * push)[:, None] * normals[head_on]
    return forces


def external_forces(
    vias: np.ndarray,
    tangents: np.ndarray,
    points: np.ndarray,
    d0: float,
    k_r: float,
    strip: str = "modified",
    head_on_ratio: float = 0.25,
    prefer: float | np.ndarray = 0.0,
    min_gap: float = 0.0,
) -> np.ndarray:
    """Dispatch to the plain (eq. 39) or modified (eq. 41) external force."""
    if strip == "plain":
        return plain_external_forces(vias, points, d0, k_r)
    if strip == "modified":
        return modified_external_forces(vias, tangents, points, d0, k_r, head_on_ratio, prefer, min_gap)
    raise ValueError(f"strip must be 'modified' or 'plain', got {strip!r}")


def unit_tangents(vias: np.ndarray) -> np.ndarray:
    """Unit direction of the strip at each via (central differences, one-sided at the ends)."""
    k = len(vias)
    t = np.zeros((k, 2))
    if k < 2:
        t[:, 0] = 1.0
        return t
    t[1:-1] = vias[2:] - vias[:-2]
    t[0] = vias[1] - vias[0]
    t[-1] = vias[-1] - vias[-2]
    n = np.linalg.norm(t, axis=1)
    bad = n < _EPS
    t[~bad] /= n[~bad, None]
    t[bad] = (1.0, 0.0)
    return t


def remove_tangential(forces: np.ndarray, tangents: np.ndarray) -> np.ndarray:
    """Forces minus their component along the strip (as in Quinlan & Khatib's elastic bands)."""
    along = np.einsum("ij,ij->i", forces, tangents)
    return forces - along[:, None] * tangents


def side_preference(vias: np.ndarray, planned: np.ndarray, tangents: np.ndarray, threshold: float) -> np.ndarray:
    """Per via: +1/-1 if it has moved more than ``threshold`` left/right of its planned point, else 0."""
    normals = np.stack([-tangents[:, 1], tangents[:, 0]], axis=1)
    lateral = np.einsum("ij,ij->i", vias - planned, normals)
    return np.where(np.abs(lateral) > threshold, np.sign(lateral), 0.0)
