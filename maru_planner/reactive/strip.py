"""The elastic strip: a fixed-size window of via points on the reference path, deformed each update."""

from __future__ import annotations

import numpy as np

from maru_planner.errors import InvalidRequest
from maru_planner.reactive.forces import (
    external_forces,
    internal_forces,
    remove_tangential,
    side_preference,
    unit_tangents,
)

MAX_REFERENCE_POINTS = 1_000_000  # resampled path points (16 MB): 300 km at the default via spacing


def resample_path(path: np.ndarray, spacing: float) -> np.ndarray:
    """Points every ``spacing`` metres along the polyline ``path`` (n, 2), both ends kept.

    InvalidRequest when that takes more than MAX_REFERENCE_POINTS points (checked before allocating).
    """
    path = np.asarray(path, dtype=float)[:, :2]
    if len(path) == 1:
        return path.copy()
    seg = np.hypot(*np.diff(path, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] < 1e-9:
        return path[:1].copy()
    if not s[-1] / spacing <= MAX_REFERENCE_POINTS:
        raise InvalidRequest(
            f"path is {s[-1]:.4g} m long: more than {MAX_REFERENCE_POINTS} vias at {spacing:g} m spacing"
        )
    count = max(int(np.ceil(s[-1] / spacing)), 1)
    targets = np.linspace(0.0, s[-1], count + 1)
    return np.stack([np.interp(targets, s, path[:, 0]), np.interp(targets, s, path[:, 1])], axis=1)


class ElasticStrip:
    """Via points on the initial path, moved by internal + external forces (eq. 36-44).

    The strip holds at most ``num_vias`` vias: via 0 is re-anchored at the
    robot every update; the others keep their deformed positions from the
    previous update (the elastic strip modifies the previous trajectory).
    When the robot passes via 1 it is dropped and the next point of the
    resampled reference path is appended, so the work per update is
    O(num_vias * obstacle points) however long the robot has been running.
    """

    def __init__(
        self,
        num_vias: int,
        spacing: float,
        k_c: float,
        k_r: float,
        d0: float,
        strip: str = "modified",
        iterations: int = 2,
        max_step: float = 0.2,
        head_on_ratio: float = 0.25,
        suppress_tangential: bool = True,
        min_gap: float = 0.0,
    ):
        if num_vias < 3:
            raise ValueError(f"num_vias must be >= 3, got {num_vias}")
        self.num_vias = num_vias
        self.spacing = spacing
        self.k_c, self.k_r, self.d0 = k_c, k_r, d0
        self.strip = strip
        self.iterations = iterations
        self.max_step = max_step
        self.head_on_ratio = head_on_ratio
        self.suppress_tangential = suppress_tangential
        self.min_gap = min_gap
        self.side_lock = 0.1  # m a via must have moved sideways before it keeps to that side (head-on rule)
        self._ref = np.zeros((0, 2))
        self._vias = np.zeros((num_vias, 2))
        self._ref_index = np.zeros(num_vias, dtype=int)
        self._count = 0
        self.pair_evaluations = 0  # via x obstacle-point distances computed, the dominant work

    def set_path(self, path: np.ndarray, start=None) -> None:
        """New reference path (n >= 1, columns x, y[, theta]); the strip restarts on it."""
        path = np.asarray(path, dtype=float)
        if path.ndim != 2 or path.shape[0] < 1 or path.shape[1] not in (2, 3):
            raise InvalidRequest(f"path must have shape (n, 2) or (n, 3), got {path.shape}")
        if not np.all(np.isfinite(path)):
            raise InvalidRequest("path contains NaN or inf")
        pts = path[:, :2]
        if start is not None:
            pts = np.vstack([np.asarray(start, dtype=float)[:2], pts])
        self._ref = resample_path(pts, self.spacing)
        self._count = min(self.num_vias, len(self._ref))
        self._vias[: self._count] = self._ref[: self._count]
        self._ref_index[: self._count] = np.arange(self._count)

    @property
    def vias(self) -> np.ndarray:
        """Current via points (k, 2), a copy."""
        return self._vias[: self._count].copy()

    @property
    def reference(self) -> np.ndarray:
        return self._ref

    def remaining_path(self) -> np.ndarray:
        """The current vias followed by the reference points not yet in the strip (m, 2)."""
        k = self._count
        return np.vstack([self._vias[:k], self._ref[self._ref_index[k - 1] + 1 :]])

    def _last_is_goal(self) -> bool:
        return self._ref_index[self._count - 1] == len(self._ref) - 1

    def _shift(self) -> None:
        k = self._count
        self._vias[1 : k - 1] = self._vias[2:k]
        self._ref_index[1 : k - 1] = self._ref_index[2:k]
        nxt = self._ref_index[k - 2] + 1
        if nxt < len(self._ref) and self._ref_index[k - 2] != len(self._ref) - 1:
            self._vias[k - 1] = self._ref[nxt]
            self._ref_index[k - 1] = nxt
        else:
            self._count -= 1

    def anchor(self, position) -> None:
        """Via 0 := robot; drop vias the robot has reached or passed (at most num_vias per call)."""
        if self._count == 0:
            raise RuntimeError("ElasticStrip has no path; call set_path first")
        p = np.asarray(position[:2], dtype=float)
        for _ in range(self.num_vias):
            if self._count < 3:
                break
            v1, v2 = self._vias[1], self._vias[2]
            reached = np.hypot(*(v1 - p)) < 0.5 * self.spacing
            # passed along the strip, or along the planned path (a strip folded behind the robot)
            i1 = self._ref_index[1]
            planned_dir = self._ref[min(i1 + 1, len(self._ref) - 1)] - self._ref[max(i1 - 1, 0)]
            passed = float(np.dot(p - v1, v2 - v1)) > 0.0 or float(np.dot(p - v1, planned_dir)) > 0.0
            if not (reached or passed):
                break
            self._shift()
        self._vias[0] = p

    def deform(self, points: np.ndarray) -> np.ndarray:
        """Apply ``iterations`` force steps to vias 1..k-1 (the goal via stays fixed); returns last forces."""
        k = self._count
        forces = np.zeros((k, 2))
        if k < 2:
            return forces
        movable_last = not self._last_is_goal()
        points = self._near_points(points)
        for _ in range(self.iterations):
            vias = self._vias[:k]
            forces = internal_forces(vias, self.k_c)
            if movable_last:
                forces[-1] = self.k_c * (self._ref[self._ref_index[k - 1]] - vias[-1])
            if len(points):
                tangents = unit_tangents(vias)
                prefer = side_preference(vias, self._ref[self._ref_index[:k]], tangents, self.side_lock)
                ext = external_forces(
                    vias, tangents, points, self.d0, self.k_r, self.strip, self.head_on_ratio, prefer, self.min_gap
                )
                if self.suppress_tangential:
                    ext = remove_tangential(ext, tangents)
                forces += ext
            self.pair_evaluations += k * len(points)
            forces[0] = 0.0
            if not movable_last:
                forces[-1] = 0.0
            norms = np.linalg.norm(forces, axis=1)
            scale = np.minimum(1.0, self.max_step / np.maximum(norms, 1e-12))
            self._vias[:k] += forces * scale[:, None]
        return forces

    def _near_points(self, points: np.ndarray) -> np.ndarray:
        """Points inside the vias' bounding box grown by d0 plus the largest move this update (the rest exert
        no force), found in O(points)."""
        if len(points) == 0:
            return points
        vias = self._vias[: self._count]
        grow = self.d0 + self.max_step * self.iterations
        lo, hi = vias.min(axis=0) - grow, vias.max(axis=0) + grow
        keep = (points[:, 0] >= lo[0]) & (points[:, 0] <= hi[0]) & (points[:, 1] >= lo[1]) & (points[:, 1] <= hi[1])
        return points[keep]

    def lookahead(self, distance: float) -> tuple[int, np.ndarray]:
        """First via at least ``distance`` along the strip from via 0 (or the last via)."""
        k = self._count
        if k == 1:
            return 0, self._vias[0].copy()
        seg = np.hypot(*np.diff(self._vias[:k], axis=0).T)
        s = np.cumsum(seg)
        idx = int(np.searchsorted(s, distance)) + 1
        idx = min(idx, k - 1)
        return idx, self._vias[idx].copy()
