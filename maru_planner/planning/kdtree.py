"""Nearest-neighbour index for a growing tree whose nodes retire (k-d tree + brute-force tail).

OMPL's ``NearestNeighbors`` structures are not exposed in its Python bindings, so RC-RRT uses
scipy's ``cKDTree`` rebuilt with doubling: nodes added since the last build sit in a small tail
searched by brute force; the tree is rebuilt (over active nodes only) when the tail holds more
than ``MAX_TAIL`` nodes. Queries skip retired (exhausted) nodes.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

MAX_TAIL = 256


class GrowingKDTree:
    """k nearest *active* points among ``points[:count]`` (``points`` is owned by the caller)."""

    def __init__(self, dim: int):
        self.dim = dim
        self._tree: cKDTree | None = None
        self._tree_ids = np.zeros(0, dtype=int)
        self._tail: list[int] = []
        self.rebuilds = 0

    def add(self, node_id: int) -> None:
        self._tail.append(node_id)

    def _rebuild(self, points: np.ndarray, active: np.ndarray, count: int) -> None:
        ids = np.flatnonzero(active[:count])
        self._tree_ids = ids
        self._tree = cKDTree(points[ids]) if len(ids) else None
        self._tail = []
        self.rebuilds += 1

    def query(self, target: np.ndarray, k: int, points: np.ndarray, active: np.ndarray, count: int) -> np.ndarray:
        """Ids of up to ``k`` active nodes nearest to ``target``, nearest first."""
        if len(self._tail) > MAX_TAIL:
            self._rebuild(points, active, count)
        cand_ids: list[np.ndarray] = []
        cand_d: list[np.ndarray] = []
        if self._tail:
            tail = np.asarray(self._tail)
            tail = tail[active[tail]]
            if len(tail):
                cand_ids.append(tail)
                diff = points[tail] - target
                cand_d.append(np.sqrt(np.einsum("ij,ij->i", diff, diff)))
        if self._tree is not None:
            ids, dists = self._query_tree(target, k, active)
            cand_ids.append(ids)
            cand_d.append(dists)
        if not cand_ids:
            return np.zeros(0, dtype=int)
        ids = np.concatenate(cand_ids)
        dists = np.concatenate(cand_d)
        if len(dists) > k:
            part = np.argpartition(dists, k - 1)[:k]
            ids, dists = ids[part], dists[part]
        return ids[np.argsort(dists, kind="stable")]

    def _query_tree(self, target, k, active):
        n = len(self._tree_ids)
        kk = min(n, 2 * k)
        while True:
            dists, idx = self._tree.query(target, k=kk)
            dists = np.atleast_1d(dists)
            idx = np.atleast_1d(idx)
            ids = self._tree_ids[idx]
            keep = active[ids]
            if keep.sum() >= k or kk >= n:
                return ids[keep], dists[keep]
            kk = min(n, kk * 4)
