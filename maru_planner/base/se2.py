"""SE(2) A* for a polygonal footprint on an occupancy grid (paper 002's complete planner).

Model (complete at its resolution):

- states are (heading index k, row, col): the reference point at a cell
  centre, heading ``k * 2 pi / K`` in the grid frame (``K`` = ``headings``,
  31 or 32 as in the paper);
- the robot at a state collides when the centre of an occupied cell lies in
  its footprint polygon (boundary included). The per-heading configuration-
  space obstacles are the grid dilated by the rotated, rasterised footprint
  (the "footprint convolution"), computed once per heading;
- moves: the 8 grid neighbours at the same heading (octile cost in metres; a
  diagonal also needs both side cells free at that heading, as in the 2-D
  A*), and turning in place to k +- 1 (cost ``rotation_weight * 2 pi / K``,
  metres per radian, default the footprint's circumradius: the arc of its
  farthest point);
- heuristic: octile distance + rotation_weight * angular distance to the goal
  heading. Translations never turn and turns never translate, so the sum is
  admissible and consistent; the first goal pop is optimal.

Stats: ``expansions`` (states popped), ``collision_checks`` (state look-ups
in the C-space layers during the search), ``cspace_cells`` (cells x headings
computed by the convolution), ``cspace_time``.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import ndimage

from maru_planner.base.astar import HAVE_NUMBA, _heap_pop, _heap_push, numba

EDGE_TOLERANCE = 1e-9


# ------------------------------------------------------------------ footprint
def as_polygon(footprint) -> np.ndarray:
    """Validate a footprint: (n >= 3, 2) finite vertices in base_link metres."""
    poly = np.asarray(footprint, dtype=float)
    if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
        raise ValueError(f"footprint must be a polygon of >= 3 (x, y) vertices, got shape {poly.shape}")
    if not np.all(np.isfinite(poly)):
        raise ValueError("footprint has non-finite vertices")
    area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    if abs(area) < 1e-12:
        raise ValueError("footprint polygon has zero area")
    return poly


def rectangle(length: float, width: float) -> np.ndarray:
    """Footprint of a length x width rectangle centred on the reference point."""
    hx, hy = length / 2.0, width / 2.0
    return np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])


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


def footprint_cells(footprint, theta: float, resolution: float) -> np.ndarray:
    """(m, 2) int offsets (drow, dcol) of cells whose centres lie in the footprint at heading theta."""
    poly = rotate(as_polygon(footprint), theta)
    reach = int(math.ceil(np.max(np.abs(poly)) / resolution)) + 1
    dr, dc = np.mgrid[-reach : reach + 1, -reach : reach + 1]
    offsets = np.column_stack([dr.ravel(), dc.ravel()])
    inside = points_in_polygon(offsets[:, ::-1] * resolution, poly)
    return offsets[inside]


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


def heading_offsets(footprint, resolution: float, headings: int) -> list[np.ndarray]:
    """footprint_cells for each heading k * 2 pi / K."""
    return [footprint_cells(footprint, 2 * math.pi * k / headings, resolution) for k in range(headings)]


def cspace_layers(occupied: np.ndarray, footprint, resolution: float, headings: int, offsets=None) -> np.ndarray:
    """(K, H, W) bool: configuration-space obstacles for each heading k * 2 pi / K.

    With numba, every occupied cell stamps the (reflected) footprint of each
    heading; otherwise one binary dilation per heading. Same result.
    """
    occupied = np.asarray(occupied, dtype=bool)
    offsets = offsets if offsets is not None else heading_offsets(footprint, resolution, headings)
    if not HAVE_NUMBA:
        return np.stack([dilate(occupied, o) for o in offsets])
    starts = np.cumsum([0] + [len(o) for o in offsets]).astype(np.int64)
    flat_offsets = np.concatenate([np.asarray(o, dtype=np.int64).reshape(-1, 2) for o in offsets])
    out = np.zeros((len(offsets),) + occupied.shape, dtype=np.bool_)
    _stamp_kernel(np.argwhere(occupied).astype(np.int64), flat_offsets, starts, out)
    return out


@(numba.njit(cache=True, nogil=True) if HAVE_NUMBA else (lambda f: f))
def _stamp_kernel(cells, offsets, starts, out):
    """out[k, r - dr, c - dc] = True for every occupied (r, c) and offset (dr, dc) of heading k."""
    num_k, height, width = out.shape
    for k in range(num_k):
        layer = out[k]
        for j in range(starts[k], starts[k + 1]):
            dr = offsets[j, 0]
            dc = offsets[j, 1]
            for i in range(cells.shape[0]):
                r = cells[i, 0] - dr
                c = cells[i, 1] - dc
                if 0 <= r < height and 0 <= c < width:
                    layer[r, c] = True


def heading_index(theta: float, headings: int) -> int:
    """Nearest discrete heading to an angle (grid frame)."""
    return int(round(theta / (2 * math.pi / headings))) % headings


# --------------------------------------------------------------------- kernel
def _njit(func):
    return numba.njit(cache=True, nogil=True)(func) if HAVE_NUMBA else func


if HAVE_NUMBA:

    @numba.njit(cache=True)
    def _now():
        with numba.objmode(t="float64"):
            t = time.perf_counter()
        return t

else:  # pragma: no cover
    _now = time.perf_counter


@_njit
def _grow(keys, gs, ids):
    n = keys.shape[0]
    k2, g2, i2 = np.empty(2 * n), np.empty(2 * n), np.empty(2 * n, dtype=np.int64)
    k2[:n] = keys
    g2[:n] = gs
    i2[:n] = ids
    return k2, g2, i2


@_njit
def _se2_kernel(blocked, starts, gr, gc, gk, rot_cost, deadline, max_expansions, initial_capacity):
    """A* over (k, r, c) on padded layers ``blocked`` (K, H, W; border blocked).

    ``starts``: (m, 3) start states (k, r, c) at cost 0; ``gk < 0`` accepts any
    goal heading. Returns (parent, goal state id or -1, cost, expansions,
    collision checks, status 0 found / 1 exhausted / 2 timed out / 3 limit).
    """
    num_k, height, width = blocked.shape
    flat = blocked.ravel()
    layer = height * width
    n = num_k * layer
    g_best = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    capacity = initial_capacity + starts.shape[0] + 1  # grows on demand (lazy duplicates)
    keys = np.empty(capacity)
    gs = np.empty(capacity)
    ids = np.empty(capacity, dtype=np.int64)
    sqrt2 = np.sqrt(2.0)
    diag_extra = sqrt2 - 1.0
    drs = np.array([0, 1, 0, -1, 1, 1, -1, -1])
    dcs = np.array([1, 0, -1, 0, 1, -1, 1, -1])
    size = 0
    checks = 0
    for i in range(starts.shape[0]):
        k, r, c = starts[i, 0], starts[i, 1], starts[i, 2]
        s = k * layer + r * width + c
        checks += 1
        if flat[s] or g_best[s] == 0.0:
            continue
        g_best[s] = 0.0
        dr = abs(r - gr)
        dc = abs(c - gc)
        h = max(dr, dc) + diag_extra * min(dr, dc)
        if gk >= 0:
            dk = abs(k - gk)
            h += rot_cost * min(dk, num_k - dk)
        size = _heap_push(keys, gs, ids, size, h, 0.0, s)
    expansions = 0
    while size > 0:
        node, g, size = _heap_pop(keys, gs, ids, size)
        if closed[node]:
            continue
        closed[node] = True
        expansions += 1
        if (expansions & 1023) == 0:
            if expansions >= max_expansions:
                return parent, -1, g, expansions, checks, 3
            if _now() > deadline:
                return parent, -1, g, expansions, checks, 2
        k = node // layer
        rem = node - k * layer
        r = rem // width
        c = rem - r * width
        if r == gr and c == gc and (gk < 0 or k == gk):
            return parent, node, g, expansions, checks, 0
        base = k * layer
        for m in range(10):
            if m < 8:
                nr = r + drs[m]
                nc = c + dcs[m]
                nk = k
                nb = base + nr * width + nc
                checks += 1
                if flat[nb] or closed[nb]:
                    continue
                if m >= 4:
                    checks += 2
                    if flat[base + nr * width + c] or flat[base + r * width + nc]:
                        continue
                    ng = g + sqrt2
                else:
                    ng = g + 1.0
            else:
                nr = r
                nc = c
                nk = (k + (1 if m == 8 else num_k - 1)) % num_k
                nb = nk * layer + rem
                checks += 1
                if flat[nb] or closed[nb]:
                    continue
                ng = g + rot_cost
            if ng < g_best[nb]:
                g_best[nb] = ng
                parent[nb] = node
                dr = abs(nr - gr)
                dc = abs(nc - gc)
                h = max(dr, dc) + diag_extra * min(dr, dc)
                if gk >= 0:
                    dk = abs(nk - gk)
                    h += rot_cost * min(dk, num_k - dk)
                if size == keys.shape[0]:
                    keys, gs, ids = _grow(keys, gs, ids)
                size = _heap_push(keys, gs, ids, size, ng + h, ng, nb)
    return parent, -1, 0.0, expansions, checks, 1


SEARCH_FOUND, SEARCH_EXHAUSTED, SEARCH_TIMED_OUT, SEARCH_LIMIT = 0, 1, 2, 3


def search_layers(
    layers: np.ndarray,
    starts,
    goal_cell,
    goal_k: int,
    rot_cost_cells: float,
    *,
    time_limit: float = math.inf,
    max_expansions: int = 2**62,
    initial_capacity: int | None = None,
) -> dict:
    """Run the SE(2) A* on (K, H, W) C-space layers (unpadded; outside = blocked).

    ``starts``: iterable of (k, row, col); ``goal_k`` -1 = any heading.
    Returns dict(status, states (n, 3) of (k, row, col), cost (cells), expansions, collision_checks).
    """
    num_k, h, w = layers.shape
    padded = np.ones((num_k, h + 2, w + 2), dtype=np.bool_)
    padded[:, 1:-1, 1:-1] = layers
    starts = np.array([[k, r + 1, c + 1] for k, r, c in starts], dtype=np.int64).reshape(-1, 3)
    deadline = time.perf_counter() + time_limit if math.isfinite(time_limit) else 1e300
    parent, goal, cost, expansions, checks, status = _se2_kernel(
        padded, starts, int(goal_cell[0]) + 1, int(goal_cell[1]) + 1, int(goal_k), float(rot_cost_cells),
        float(deadline), int(max_expansions),
        int(initial_capacity if initial_capacity is not None else min(10 * padded.size, 1 << 20)),
    )
    states = np.zeros((0, 3), dtype=np.int64)
    if status == SEARCH_FOUND:
        ids = [int(goal)]
        while parent[ids[-1]] >= 0:
            ids.append(int(parent[ids[-1]]))
        ids = np.array(ids[::-1], dtype=np.int64)
        layer = (h + 2) * (w + 2)
        k, rem = ids // layer, ids % layer
        states = np.column_stack([k, rem // (w + 2) - 1, rem % (w + 2) - 1])
    return {
        "status": int(status),
        "states": states,
        "cost": float(cost) if status == SEARCH_FOUND else math.inf,
        "expansions": int(expansions),
        "collision_checks": int(checks),
    }


class SE2AStarPlanner:
    """Complete SE(2) A* for a polygonal footprint (see the module docstring)."""

    def __init__(self, footprint, headings: int = 32, rotation_weight: float | None = None, time_limit: float = 60.0):
        self.footprint = as_polygon(footprint)
        if int(headings) < 1:
            raise ValueError(f"headings must be >= 1, got {headings}")
        self.headings = int(headings)
        r_in, r_out = footprint_radii(self.footprint)
        self.r_in, self.r_out = r_in, r_out
        self.rotation_weight = r_out if rotation_weight is None else float(rotation_weight)
        if not (math.isfinite(self.rotation_weight) and self.rotation_weight >= 0):
            raise ValueError(f"rotation_weight must be finite and >= 0, got {rotation_weight}")
        if not time_limit > 0:
            raise ValueError(f"time_limit must be > 0 s, got {time_limit}")
        self.time_limit = float(time_limit)
        self._offsets: dict[float, list[np.ndarray]] = {}

    def offsets(self, resolution: float) -> list[np.ndarray]:
        """Rasterised footprint per heading, cached per resolution."""
        if resolution not in self._offsets:
            self._offsets[resolution] = heading_offsets(self.footprint, resolution, self.headings)
        return self._offsets[resolution]

    def rot_cost_cells(self, resolution: float) -> float:
        return self.rotation_weight * (2 * math.pi / self.headings) / resolution

    def check_endpoints(self, grid, start, goal):
        """Validate poses; returns (start cell, goal cell, start k, goal k) or raises RequestError."""
        from maru_planner.base import common

        common.check_grid(grid)
        start, goal = common.as_pose(start, "start"), common.as_pose(goal, "goal")
        cells = []
        for name, pose in (("start", start), ("goal", goal)):
            cell = common.pose_cell(grid, pose, name)
            k = heading_index(grid.heading_to_grid(pose[2]), self.headings)
            if offsets_collide(grid.occupied, self.offsets(grid.resolution)[k], cell[0], cell[1]):
                raise common.occupied_error(name, pose, "the footprint covers an occupied cell")
            cells.append((cell, k))
        return cells[0][0], cells[1][0], cells[0][1], cells[1][1]

    def plan(self, grid, start, goal):
        from maru_planner.base import common

        t0 = time.perf_counter()
        stats = {"expansions": 0, "collision_checks": 0, "planning_time": 0.0, "deciding_stage": "full",
                 "headings": self.headings}
        try:
            s_cell, g_cell, sk, gk = self.check_endpoints(grid, start, goal)
        except common.RequestError as exc:
            stats["planning_time"] = time.perf_counter() - t0
            return common.failure(exc.status, str(exc), stats)
        stats.update(self.search(grid, s_cell, g_cell, sk, gk, self.time_limit - (time.perf_counter() - t0)))
        return self.finish(grid, stats, t0, "solved by full SE(2) A*")

    def search(self, grid, s_cell, g_cell, sk, gk, time_limit) -> dict:
        """C-space layers for the whole map, then the search; returns stats + states."""
        t = time.perf_counter()
        layers = cspace_layers(grid.occupied, self.footprint, grid.resolution, self.headings,
                               self.offsets(grid.resolution))
        cspace_time = time.perf_counter() - t
        out = search_layers(layers, [(sk, *s_cell)], g_cell, gk, self.rot_cost_cells(grid.resolution),
                            time_limit=max(time_limit - cspace_time, 1e-3))
        out.update(cspace_time=cspace_time, cspace_cells=int(layers.size), search_time=time.perf_counter() - t)
        return out

    def finish(self, grid, stats: dict, t0: float, solved_message: str, layers: dict | None = None):
        from maru_planner.base import common
        from maru_planner.base import result as R

        states = stats.pop("states")
        status = stats.pop("status")
        stats["planning_time"] = time.perf_counter() - t0
        if status == SEARCH_FOUND:
            stats["cost"] = stats["cost"] * grid.resolution
            path = common.states_to_path(grid, states, self.headings)
            return R.BasePlanResult(R.SOLVED, solved_message, path, stats, layers or {})
        stats.pop("cost", None)
        if status == SEARCH_TIMED_OUT:
            return common.failure(R.TIMED_OUT, f"SE(2) A* timed out after {stats['planning_time']:.3f} s", stats,
                                  layers)
        return common.failure(R.NO_PATH, "no path: SE(2) A* exhausted the free configurations", stats, layers)
