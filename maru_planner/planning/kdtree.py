"""Nearest-neighbour index for a growing tree whose nodes retire (k-d tree + brute-force tail).

OMPL's ``NearestNeighbors`` structures are not exposed in its Python bindings, so RC-RRT uses
scipy's ``cKDTree``: nodes added since the last build sit in a small tail searched by brute force
(one vectorised distance computation); the tree is rebuilt (over active nodes only) when the tail
holds more than ``MAX_TAIL`` nodes. Queries skip retired (exhausted) nodes.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

MAX_TAIL = 256


class GrowingKDTree:
    """k nearest *active* points among ``points[:count]`` (``points`` and ``active`` are the caller's).

    Nodes get consecutive ids, so the tail is the id range ``[tail_start, count)``; nothing needs
    registering: a node is indexed by existing in ``points[:count]``.
    """

    def __init__(self) -> None:
        self._tree: cKDTree | None = None
        self._tree_ids = np.zeros(0, dtype=int)
        self._tail_start = 0

    def _rebuild(self, points: np.ndarray, active: np.ndarray, count: int) -> None:
        ids = np.flatnonzero(active[:count])
        self._tree_ids = ids
        self._tree = cKDTree(points[ids]) if len(ids) else None
        self._tail_start = count

    def query(self, target: np.ndarray, k: int, points: np.ndarray, active: np.ndarray, count: int) -> np.ndarray:
        """Ids of up to ``k`` active nodes nearest to ``target``, nearest first."""
        if count - self._tail_start > MAX_TAIL:
            self._rebuild(points, active, count)
        ts = self._tail_start
        diff = points[ts:count] - target
        dists = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        keep = active[ts:count]
        ids = np.arange(ts, count)[keep]
        dists = dists[keep]
        if self._tree is not None:
            tids, tdists = self._query_tree(target, k, active)
            ids = np.concatenate([ids, tids])
            dists = np.concatenate([dists, tdists])
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
