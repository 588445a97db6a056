"""Vectorised 2-D geometry for the simulator: rays against circles/segments, distances, containment."""

from __future__ import annotations

import numpy as np

_EPS = 1e-12


def rays_vs_circles(origin: np.ndarray, dirs: np.ndarray, circles: np.ndarray, max_range: float) -> np.ndarray:
    """Distance along each unit ray (B, 2) from ``origin`` to the first circle (N, 3: x, y, r); inf if none.

    A ray starting inside a circle reads 0.
    """
    out = np.full(len(dirs), np.inf)
    if len(circles) == 0:
        return out
    rel = circles[:, :2] - origin  # (N, 2)
    dist = np.hypot(rel[:, 0], rel[:, 1])
    keep = dist - circles[:, 2] <= max_range
    if not np.any(keep):
        return out
    rel, radius = rel[keep], circles[keep, 2]
    proj = dirs @ rel.T  # (B, N)
    perp2 = np.sum(rel * rel, axis=1)[None, :] - proj * proj
    disc = radius[None, :] ** 2 - perp2
    hit = disc >= 0.0
    root = np.sqrt(np.where(hit, disc, 0.0))
    t_near = proj - root
    t_far = proj + root
    t = np.where(t_near >= 0.0, t_near, 0.0)
    t = np.where(hit & (t_far >= 0.0), t, np.inf)
    return np.minimum(out, t.min(axis=1))


def fan_vs_circles(
    origin: np.ndarray, angle0: float, increment: float, count: int, circles: np.ndarray, max_range: float
) -> np.ndarray:
    """Like :func:`rays_vs_circles` for a fan of ``count`` rays at ``angle0 + k * increment`` (fan < 360 deg).

    Only the beams inside each circle's angular extent are tested, so the
    cost is O(beams + hit pairs) instead of O(beams x circles).
    """
    out = np.full(count, np.inf)
    if len(circles) == 0:
        return out
    rel = circles[:, :2] - origin
    dist = np.hypot(rel[:, 0], rel[:, 1])
    radius = circles[:, 2]
    inside = dist <= radius
    if np.any(inside):
        return np.zeros(count)
    keep = dist - radius <= max_range
    rel, dist, radius = rel[keep], dist[keep], radius[keep]
    half_fan = 0.5 * increment * (count - 1)
    mid = angle0 + half_fan
    offset = (np.arctan2(rel[:, 1], rel[:, 0]) - mid + np.pi) % (2 * np.pi) - np.pi
    half = np.arcsin(np.clip(radius / dist, 0.0, 1.0))
    lo = np.maximum(np.ceil((offset - half + half_fan) / increment - 1e-9), 0).astype(int)
    hi = np.minimum(np.floor((offset + half + half_fan) / increment + 1e-9), count - 1).astype(int)
    n = np.maximum(hi - lo + 1, 0)
    total = int(n.sum())
    if total == 0:
        return out
    circle = np.repeat(np.arange(len(n)), n)
    start = np.cumsum(n) - n
    beam = lo[circle] + (np.arange(total) - start[circle])
    angles = angle0 + increment * beam
    proj = np.cos(angles) * rel[circle, 0] + np.sin(angles) * rel[circle, 1]
    disc = radius[circle] ** 2 - (dist[circle] ** 2 - proj * proj)
    t = np.where((disc >= 0) & (proj > 0), proj - np.sqrt(np.maximum(disc, 0.0)), np.inf)
    np.minimum.at(out, beam, t)
    return out


def rays_vs_segments(origin: np.ndarray, dirs: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance along each unit ray (B, 2) to the first segment (M, 4: ax, ay, bx, by); inf if none."""
    out = np.full(len(dirs), np.inf)
    if len(segments) == 0:
        return out
    a = segments[:, :2] - origin
    e = segments[:, 2:] - segments[:, :2]
    denom = dirs[:, None, 0] * e[None, :, 1] - dirs[:, None, 1] * e[None, :, 0]  # cross(u, e)
    ok = np.abs(denom) > _EPS
    denom = np.where(ok, denom, 1.0)
    t = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / denom  # cross(a, e) / cross(u, e)
    s = (a[None, :, 0] * dirs[:, None, 1] - a[None, :, 1] * dirs[:, None, 0]) / denom  # cross(a, u) / cross(u, e)
    valid = ok & (t >= 0.0) & (s >= 0.0) & (s <= 1.0)
    return np.minimum(out, np.where(valid, t, np.inf).min(axis=1))


def points_to_segments(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance from each point (P, 2) to each segment (M, 4): (P, M)."""
    a = segments[None, :, :2]
    e = segments[None, :, 2:] - segments[None, :, :2]
    rel = points[:, None, :] - a
    denom = np.maximum(np.sum(e * e, axis=2), _EPS)
    s = np.clip(np.sum(rel * e, axis=2) / denom, 0.0, 1.0)
    closest = a + s[..., None] * e
    diff = points[:, None, :] - closest
    return np.hypot(diff[..., 0], diff[..., 1])


def point_in_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd rule: which points (P, 2) lie inside ``polygon`` (V, 2)."""
    x, y = points[:, 0:1], points[:, 1:2]
    xa, ya = polygon[:, 0][None, :], polygon[:, 1][None, :]
    xb, yb = np.roll(polygon[:, 0], -1)[None, :], np.roll(polygon[:, 1], -1)[None, :]
    crosses = (ya > y) != (yb > y)
    x_int = xa + (y - ya) * (xb - xa) / np.where(yb == ya, _EPS, yb - ya)
    return np.sum(crosses & (x < x_int), axis=1) % 2 == 1


def polygon_segments(polygon: np.ndarray) -> np.ndarray:
    """Closed polygon (V, 2) -> its edges (V, 4)."""
    return np.hstack([polygon, np.roll(polygon, -1, axis=0)])


def segments_intersect(s1: np.ndarray, s2: np.ndarray) -> bool:
    """Does any segment of s1 (A, 4) properly cross any of s2 (B, 4)?"""
    if len(s1) == 0 or len(s2) == 0:
        return False
    p, r = s1[:, None, :2], (s1[:, 2:] - s1[:, :2])[:, None, :]
    q, s = s2[None, :, :2], (s2[:, 2:] - s2[:, :2])[None, :, :]
    rxs = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    qp = q - p
    ok = np.abs(rxs) > _EPS
    rxs = np.where(ok, rxs, 1.0)
    t = (qp[..., 0] * s[..., 1] - qp[..., 1] * s[..., 0]) / rxs
    u = (qp[..., 0] * r[..., 1] - qp[..., 1] * r[..., 0]) / rxs
    return bool(np.any(ok & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)))


def box_polygon(center, size, yaw: float = 0.0) -> np.ndarray:
    """Corners (4, 2) of a box of ``size`` (length x, width y) centred at ``center`` rotated by ``yaw``."""
    hx, hy = 0.5 * size[0], 0.5 * size[1]
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    return corners @ rot.T + np.asarray(center, dtype=float)


def transform(points: np.ndarray, pose) -> np.ndarray:
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + np.array([pose[0], pose[1]])
