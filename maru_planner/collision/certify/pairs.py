"""The pairs a certification proves, as arrays: (moving geometry, obstacle) pairs and the robot's self pairs, with
what bounds each pair's distance (bounding volumes, obstacle bounding boxes, the kernels' primitives)."""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from maru_planner.collision.spheres import ScenePrimitives
from maru_planner.scene import Obstacle

UNBOUNDED = 1e6  # m: an obstacle bounding box this large is treated as infinite


@dataclass
class PairTable:
    """The pairs to prove as arrays: (moving geometry, obstacle) for a list of obstacles, then the self pairs.

    Obstacle pairs are measured by coal directly (a Pinocchio geometry model of thousands of obstacles takes
    minutes to build: each added object resizes its pair matrix), self pairs through the robot's own model.
    """

    obstacles: list  # per obstacle: (geometry, its convex hull or itself, placement)
    self_pair: np.ndarray  # (P,) index into the robot model's collision pairs (-1 for an obstacle pair)
    has_hull: np.ndarray  # (P,) bool: a mesh in the pair (its hull distance is a cheaper lower bound)
    first: np.ndarray  # (P,) robot geometry
    second: np.ndarray  # (P,) robot geometry, or obstacle index (into the box arrays) for obstacle pairs
    obstacle: np.ndarray  # (P,) bool
    other: np.ndarray  # (P,) the second robot geometry of a self pair (the first for an obstacle pair)
    moves_first: np.ndarray  # (P, nq) bool: joints that move the first body but not the second
    moves_other: np.ndarray  # (P, nq) bool: joints that move the second (robot) body but not the first
    rate: np.ndarray  # (P, nq): distance change per unit |dq_j|
    gap: np.ndarray  # (P,): exact distance - bounding-volume bound is at most this
    box_center: np.ndarray  # (K, 3) obstacle bounding boxes in the world
    box_rot: np.ndarray  # (K, 3, 3)
    box_half: np.ndarray  # (K, 3)
    covered: np.ndarray  # (P,) bool: a sphere-cover bound applies (mesh geometries, bounded obstacle primitives)
    measure: np.ndarray  # (P,) MEASURE_*: what the row kernel's GJK bound (support_bounds) is for the pair
    primitives: tuple  # the obstacles' sphere-kernel primitives (boxes, spheres, cylinders) and each one's index

    @property
    def arrays(self) -> tuple:
        """The per-pair arrays :func:`assess_rows_nb` takes, in its order."""
        return (self.first, self.second, self.obstacle, self.other, self.covered, self.measure, self.moves_first,
                self.moves_other, self.gap, self.box_center, self.box_rot, self.box_half)  # fmt: skip


def kernel_primitives(obstacles: list[Obstacle]) -> tuple[tuple, np.ndarray]:
    """The obstacles' sphere-kernel primitives (each contains its obstacle): the index of each obstacle's
    primitive, then the arrays :func:`~maru_planner.collision.kernels.primitives.obstacle_distance` takes; and per
    obstacle whether its primitive is the obstacle itself."""
    primitives = ScenePrimitives.from_obstacles(obstacles)
    kernel_index = {id(ob): k for k, ob in enumerate(primitives.obstacles)}
    position = np.array([kernel_index[id(ob)] for ob in obstacles], dtype=np.int64)
    return (position, *primitives.as_tuple()[:-1]), primitives.exact[position]


def box_distances(centers: np.ndarray, box_center: np.ndarray, box_rot: np.ndarray, box_half: np.ndarray
                   ) -> np.ndarray:  # fmt: skip
    """(points, boxes): distance from each of ``centers`` (n, 3) to each box (0 inside)."""
    offset = centers[:, None, :] - box_center[None]  # (points, boxes, 3)
    local = sum(offset[..., b, None] * box_rot[:, b] for b in range(3))  # R^T offset (5x faster than einsum here)
    return np.linalg.norm(np.maximum(np.abs(local) - box_half, 0.0), axis=2)


def bounding_box(geometry: coal.CollisionGeometry, placement: pin.SE3
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:  # fmt: skip
    """World centre, rotation and half extents of a fixed obstacle's bounding box; True if it is the obstacle."""
    geometry.computeLocalAABB()
    lo, hi = np.asarray(geometry.aabb_local.min_, dtype=float), np.asarray(geometry.aabb_local.max_, dtype=float)
    if not (np.abs(lo).max() < UNBOUNDED and np.abs(hi).max() < UNBOUNDED):  # a half-space: coal decides each query
        return placement.translation.copy(), placement.rotation.copy(), np.full(3, np.inf), False
    return placement.act(0.5 * (lo + hi)), placement.rotation.copy(), 0.5 * (hi - lo), isinstance(geometry, coal.Box)
