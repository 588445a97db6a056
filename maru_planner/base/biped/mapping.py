"""3-D → 2-D mapping of paper 004: line obstacles and virtual obstacles.

Each box is compared with the robot's height bands:

* ``z_max <= step_height``: the feet step over or onto it → no obstacle;
* ``z_min >= height``: above the robot → no obstacle;
* it reaches the leg band ``(step_height, body_bottom)`` → **line obstacle**:
  what the gait rectangle (width w_k) touches; its footprint as is;
* it reaches the body band ``(body_bottom, height)`` → **virtual obstacle**:
  what the body (width w_r) touches; the footprint grown by the body's
  overhang beyond the gait rectangle, eq. 1 for a symmetric robot
  (``(w_r − w_k)/2``) and eq. 2–3 for an asymmetric one: obstacles in the
  right half-plane of the line S grow by ``d_R``, those in the left by ``d_L``.

The planners then move the gait rectangle among both kinds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from maru_planner.base.biped.world import BipedRobot, BipedWorld, Box3D, grid_shape
from maru_planner.base.budget import Deadline, unlimited
from maru_planner.base.grid import OccupancyGrid

_STRIP_ROWS = 128  # rows per distance transform when the clearance is capped

STEPPABLE, LINE, VIRTUAL, LINE_AND_VIRTUAL, OVERHEAD = "steppable", "line", "virtual", "line+virtual", "overhead"


def classify(box: Box3D, robot: BipedRobot) -> str:
    """Which obstacle a box becomes for this robot."""
    zmin, zmax = box.z
    if zmin >= robot.height:
        return OVERHEAD
    if zmax <= robot.step_height and zmin <= robot.step_height:
        return STEPPABLE
    legs = zmin < robot.body_bottom and zmax > robot.step_height
    body = zmax > robot.body_bottom and zmin < robot.height
    if legs and body:
        return LINE_AND_VIRTUAL
    return LINE if legs else VIRTUAL


@dataclass
class BipedMap2D:
    """The 2-D map the biped planners use; row = y index, col = x index."""

    line: np.ndarray  # line obstacles (footprints the gait touches)
    virtual: np.ndarray  # virtual obstacles (body footprints grown by the overhang)
    resolution: float
    origin: tuple  # (x, y) of the lower-left corner
    classes: dict = field(default_factory=dict)  # obstacle name -> class
    growth: dict = field(default_factory=dict)  # obstacle name -> clearance added (m)

    @property
    def occupied(self) -> np.ndarray:
        return self.line | self.virtual

    @property
    def shape(self) -> tuple:
        return self.line.shape

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        return int(math.floor((y - self.origin[1]) / self.resolution)), int(
            math.floor((x - self.origin[0]) / self.resolution)
        )

    def cell_to_world(self, row: float, col: float) -> tuple[float, float]:
        return self.origin[0] + (col + 0.5) * self.resolution, self.origin[1] + (row + 0.5) * self.resolution

    def clearance(self, cap: float = math.inf, deadline: Deadline | None = None) -> np.ndarray:
        """Metres from each cell centre to the nearest obstacle cell's edge (map border counts as obstacle).

        Values above ``cap`` come out as ``cap``: with a finite cap the transform runs in strips of
        rows (each seeing the obstacles within ``cap`` around it) and checks ``deadline`` between them.
        """
        deadline = deadline or unlimited()
        free = ~self.occupied
        height = free.shape[0]
        reach = height if not math.isfinite(cap) else int(math.ceil(cap / self.resolution)) + 2
        out = np.empty(free.shape)
        for top in range(0, height, _STRIP_ROWS):
            deadline.check_now("computing the clearance")
            bottom = min(top + _STRIP_ROWS, height)
            lo, hi = max(top - reach, 0), min(bottom + reach, height)
            pad_top, pad_bottom = int(lo == 0), int(hi == height)
            padded = np.pad(free[lo:hi], ((pad_top, pad_bottom), (1, 1)), constant_values=False)
            dist = ndimage.distance_transform_edt(padded)[pad_top : pad_top + hi - lo, 1:-1]
            strip = dist[top - lo : bottom - lo] * self.resolution - self.resolution / 2
            out[top:bottom] = np.minimum(np.maximum(strip, 0.0), cap)
        return out

    def to_occupancy_grid(self):
        """As a ``maru_planner.base.grid.OccupancyGrid`` (for the CLI, the node and A*)."""
        return OccupancyGrid(self.occupied, self.resolution, (self.origin[0], self.origin[1], 0.0))


def _stamp_box(box: Box3D, target: np.ndarray, resolution: float, origin) -> None:
    """Mark in ``target`` the cells whose centre lies inside the box footprint (only its bounding window is read)."""
    rows, cols = target.shape
    reach = math.hypot(*box.size) / 2 + resolution
    c0 = max(int(math.floor((box.center[0] - reach - origin[0]) / resolution)), 0)
    c1 = min(int(math.ceil((box.center[0] + reach - origin[0]) / resolution)) + 1, cols)
    r0 = max(int(math.floor((box.center[1] - reach - origin[1]) / resolution)), 0)
    r1 = min(int(math.ceil((box.center[1] + reach - origin[1]) / resolution)) + 1, rows)
    if c0 >= c1 or r0 >= r1:
        return
    xs = origin[0] + (np.arange(c0, c1) + 0.5) * resolution
    ys = origin[1] + (np.arange(r0, r1) + 0.5) * resolution
    gx, gy = np.meshgrid(xs, ys)
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    dx, dy = gx - box.center[0], gy - box.center[1]
    u, v = c * dx + s * dy, -s * dx + c * dy
    tol = 1e-9
    target[r0:r1, c0:c1] |= (np.abs(u) <= box.size[0] / 2 + tol) & (np.abs(v) <= box.size[1] / 2 + tol)


def side_of_line(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """+1 for points in the left half-plane of polyline S (by its nearest segment), −1 for the right."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    a, b = line[:-1], line[1:]
    ab = b - a
    length2 = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    ap = points[:, None, :] - a[None, :, :]
    t = np.clip(np.sum(ap * ab[None], axis=2) / length2[None], 0.0, 1.0)
    nearest = a[None] + t[..., None] * ab[None]
    seg = np.argmin(np.sum((points[:, None, :] - nearest) ** 2, axis=2), axis=1)
    cross = ab[seg, 0] * ap[np.arange(len(points)), seg, 1] - ab[seg, 1] * ap[np.arange(len(points)), seg, 0]
    return np.where(cross >= 0, 1, -1)


def _grow(mask: np.ndarray, radius: float, resolution: float) -> np.ndarray:
    if radius <= 0 or not mask.any():
        return mask.copy()
    dist = ndimage.distance_transform_edt(~mask) * resolution
    return dist <= radius + 1e-9


def map_3d_to_2d(world: BipedWorld, reference_line: np.ndarray | None = None) -> BipedMap2D:
    """The 2-D map of line and virtual obstacles for ``world.robot`` (eq. 1–3)."""
    robot = world.robot
    res = world.resolution
    shape = grid_shape(world.bounds, res)
    origin = (world.bounds[0], world.bounds[1])
    line = np.zeros(shape, dtype=bool)
    body_left = np.zeros(shape, dtype=bool)
    body_right = np.zeros(shape, dtype=bool)
    classes, growth = {}, {}
    if reference_line is None:
        reference_line = world.reference_line
    if reference_line is None and world.start is not None and world.goal is not None:
        reference_line = np.array([world.start[:2], world.goal[:2]], dtype=float)
    for box in world.obstacles:
        kind = classify(box, robot)
        classes[box.name] = kind
        if kind in (LINE, LINE_AND_VIRTUAL):
            _stamp_box(box, line, res, origin)
        if kind not in (VIRTUAL, LINE_AND_VIRTUAL):
            continue
        if robot.symmetric or reference_line is None:
            side = 1
            grow = max(robot.overhang_left, robot.overhang_right)
        else:
            side = int(side_of_line(np.asarray(box.center)[None], np.asarray(reference_line, dtype=float))[0])
            grow = robot.overhang_left if side > 0 else robot.overhang_right
        growth[box.name] = grow
        _stamp_box(box, body_left if side > 0 else body_right, res, origin)
    virtual = np.zeros(shape, dtype=bool)
    if robot.symmetric or reference_line is None:
        virtual |= _grow(body_left | body_right, max(robot.overhang_left, robot.overhang_right), res)
    else:
        virtual |= _grow(body_left, robot.overhang_left, res) | _grow(body_right, robot.overhang_right, res)
    return BipedMap2D(line, virtual, res, origin, classes, growth)


def wheeled_map(world: BipedWorld) -> np.ndarray:
    """What a wheeled robot of the same body would see: every box under ``height`` is an obstacle."""
    robot = world.robot
    res = world.resolution
    occ = np.zeros(grid_shape(world.bounds, res), dtype=bool)
    for box in world.obstacles:
        if box.z[0] < robot.height:
            _stamp_box(box, occ, res, world.bounds[:2])
    return occ
