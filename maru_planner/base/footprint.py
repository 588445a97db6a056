"""Robot footprints: polygon checks, radii, rasterisation per heading (the cells a pose covers).

A footprint is an (n >= 3, 2) polygon in base_link metres around the reference point. The robot
at cell (row, col) and heading theta (grid frame) covers the cells whose centres lie in the
rotated polygon (boundary included, within EDGE_TOLERANCE metres).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from maru_planner.base.budget import Deadline, check_bytes, unlimited
from maru_planner.errors import InvalidRequest

EDGE_TOLERANCE = 1e-9
_CHUNK_POINTS = 1 << 16  # points tested per numpy call while rasterising (bounds temporaries and deadline lag)


def as_polygon(footprint) -> np.ndarray:
    """Validate a footprint: (n >= 3, 2) finite vertices in base_link metres, non-zero area."""
    try:
        poly = np.asarray(footprint, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidRequest(f"footprint must be (x, y) vertices: {exc}") from None
    if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
        raise InvalidRequest(f"footprint must be a polygon of >= 3 (x, y) vertices, got shape {poly.shape}")
    if not np.all(np.isfinite(poly)):
        raise InvalidRequest("footprint has non-finite vertices")
    area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    if abs(area) < 1e-12:
        raise InvalidRequest("footprint polygon has zero area")
    return poly


def rectangle(length: float, width: float) -> np.ndarray:
    """Footprint of a length x width rectangle centred on the reference point (both > 0)."""
    if not (math.isfinite(length) and math.isfinite(width) and length > 0 and width > 0):
        raise InvalidRequest(f"rectangle footprint needs length and width > 0 m, got {length} x {width}")
    hx, hy = length / 2.0, width / 2.0
    return np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])


def disc(radius: float, sides: int = 16) -> np.ndarray:
    """A regular polygon circumscribing the disc of ``radius`` (> 0) about the reference point."""
    if not (math.isfinite(radius) and radius > 0):
        raise InvalidRequest(f"disc footprint needs a radius > 0 m, got {radius}")
    angles = np.linspace(0.0, 2 * math.pi, sides, endpoint=False)
    r = radius / math.cos(math.pi / sides)
    return np.column_stack([r * np.cos(angles), r * np.sin(angles)])


def _segment_distances(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance from each point to the polygon boundary."""
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    ap = points[:, None, :] - a[None, :, :]
    t = np.clip(np.sum(ap * ab, axis=2) / np.maximum(np.sum(ab * ab, axis=1), 1e-300), 0.0, 1.0)
    closest = a[None, :, :] + t[..., None] * ab[None, :, :]
    return np.min(np.linalg.norm(points[:, None, :] - closest, axis=2), axis=1)


def points_in_polygon(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Inside or on the boundary (within EDGE_TOLERANCE metres)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    x, y = points[:, 0:1], points[:, 1:2]
    x0, y0 = poly[:, 0][None, :], poly[:, 1][None, :]
    x1, y1 = np.roll(poly[:, 0], -1)[None, :], np.roll(poly[:, 1], -1)[None, :]
    crosses = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    inside = np.sum(crosses & (x < x_at), axis=1) % 2 == 1
    return inside | (_segment_distances(points, poly) <= EDGE_TOLERANCE)


def footprint_radii(footprint) -> tuple[float, float]:
    """(inscribed, circumscribed) radius about the reference point.

    The inscribed radius is the distance from the reference point to the
    polygon's boundary (0 when the point is outside): the disc of that radius
    lies in the robot at every heading (paper 002's half minimum width for a
    centred footprint). The circumscribed radius is the farthest vertex: the
    robot lies in that disc at every heading (half the maximum width).
    """
    poly = as_polygon(footprint)
    origin = np.zeros((1, 2))
    inner = float(_segment_distances(origin, poly)[0]) if points_in_polygon(origin, poly)[0] else 0.0
    return inner, float(np.max(np.linalg.norm(poly, axis=1)))


def rotate(poly: np.ndarray, theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return poly @ np.array([[c, s], [-s, c]])


def footprint_cells(
    footprint, theta: float, resolution: float, max_reach: int | None = None, deadline: Deadline | None = None
) -> np.ndarray:
    """(m, 2) int offsets (drow, dcol) of cells whose centres lie in the footprint at heading theta.

    ``max_reach`` clips the offsets to |drow|, |dcol| <= max_reach (a map of H x W cells never
    needs more than max(H, W) - 1: farther offsets cannot reach from one of its cells to another).
    """
    deadline = deadline or unlimited()
    poly = rotate(as_polygon(footprint), theta)
    reach = int(math.ceil(np.max(np.abs(poly)) / resolution)) + 1
    if max_reach is not None:
        reach = min(reach, max_reach)
    cols = np.arange(-reach, reach + 1)
    rows_per_chunk = max(1, _CHUNK_POINTS // len(cols))
    found = []
    for first in range(-reach, reach + 1, rows_per_chunk):
        deadline.check_now("rasterising the footprint")
        dr, dc = np.meshgrid(np.arange(first, min(first + rows_per_chunk, reach + 1)), cols, indexing="ij")
        offsets = np.column_stack([dr.ravel(), dc.ravel()])
        found.append(offsets[points_in_polygon(offsets[:, ::-1] * resolution, poly)])
    return np.concatenate(found)


def footprint_collides(occupied: np.ndarray, footprint, resolution: float, row: int, col: int, theta: float) -> bool:
    """Does the footprint at cell (row, col), heading theta (grid frame) cover an occupied cell centre?"""
    return offsets_collide(occupied, footprint_cells(footprint, theta, resolution), row, col)


def offsets_collide(occupied: np.ndarray, offsets: np.ndarray, row: int, col: int) -> bool:
    """Is any cell (row + dr, col + dc) inside the map occupied?"""
    offsets = offsets + np.array([row, col])
    h, w = occupied.shape
    keep = (offsets[:, 0] >= 0) & (offsets[:, 0] < h) & (offsets[:, 1] >= 0) & (offsets[:, 1] < w)
    offsets = offsets[keep]
    return bool(occupied[offsets[:, 0], offsets[:, 1]].any())


def dilate(occupied: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """out[r, c] = any occupied[r + dr, c + dc] over the offsets (outside the map counts as free)."""
    if len(offsets) == 0 or not occupied.any():
        return np.zeros_like(occupied, dtype=bool)
    reach = int(np.max(np.abs(offsets)))
    # scipy's dilation reflects the structuring element: store the offsets negated
    structure = np.zeros((2 * reach + 1, 2 * reach + 1), dtype=bool)
    structure[reach - offsets[:, 0], reach - offsets[:, 1]] = True
    return ndimage.binary_dilation(occupied, structure=structure, border_value=0)


def heading_offsets(
    footprint,
    resolution: float,
    headings: int,
    map_shape: tuple[int, int] | None = None,
    deadline: Deadline | None = None,
) -> list[np.ndarray]:
    """footprint_cells for each heading k * 2 pi / K, clipped to what a map of ``map_shape`` can use.

    Refuses (TooLarge) up front when the rasters would not fit the memory limit.
    """
    poly = as_polygon(footprint)
    max_reach = max(map_shape) - 1 if map_shape is not None else None
    reach = math.ceil(np.max(np.linalg.norm(poly, axis=1)) / resolution) + 1
    side = 2 * min(reach, max_reach if max_reach is not None else reach) + 1
    area = abs(0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1]))
    cells = min(area / resolution**2 + 4 * reach, side * side)
    check_bytes(
        headings * cells * 16.0,
        f"rasterising the footprint ({cells:.0f} cells) at {headings} headings",
        "use a smaller footprint, a coarser map or fewer headings",
    )
    return [footprint_cells(poly, 2 * math.pi * k / headings, resolution, max_reach, deadline) for k in range(headings)]


def heading_index(theta: float, headings: int) -> int:
    """Nearest discrete heading to an angle (grid frame)."""
    return int(round(theta / (2 * math.pi / headings))) % headings
