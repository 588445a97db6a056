"""The order in which an edge's states are checked: its end first, then the midpoints of ever finer halves.

Plain Python and numpy on purpose: the exact checker orders its batches with :func:`bisection_order` without
loading numba, and the edge kernels compile :func:`bisection_order_into` itself (:mod:`.edge_validity`).
"""

from __future__ import annotations

import numpy as np

MAX_CACHED = 4096  # orders bisection_order keeps (by n and include_first)
_CACHE: dict[tuple[int, bool], np.ndarray] = {}


def bisection_order(n: int, include_first: bool = True) -> np.ndarray:
    """Indices 0..n-1: last, first, then midpoints of ever finer halves (cached per n).

    ``include_first=False`` is for edge states that exclude the (already valid) edge start:
    index 0 is then one step from it and is not moved to the front.
    """
    key = (n, include_first)
    order = _CACHE.get(key)
    if order is None:
        order, queue = np.empty(n, dtype=np.int64), np.empty((2 * n + 1, 2), dtype=np.int64)
        if n > 0:
            bisection_order_into(n, order, queue, include_first)
        if len(_CACHE) < MAX_CACHED:
            _CACHE[key] = order
    return order


def bisection_order_into(n: int, out: np.ndarray, queue: np.ndarray, include_first: bool) -> None:
    """:func:`bisection_order` of ``n`` (> 0) into ``out[:n]``; ``queue`` ((2n + 1, 2) int64) holds the segments still
    to halve (each midpoint adds two)."""
    out[0] = n - 1
    filled, first = 1, -1
    if include_first and n > 1:
        out[1] = 0
        filled, first = 2, 0
    queue[0, 0], queue[0, 1] = first, n - 1
    head, tail = 0, 1
    while head < tail:
        a, b = queue[head, 0], queue[head, 1]
        head += 1
        if b - a < 2:
            continue
        m = (a + b) // 2
        out[filled] = m
        filled += 1
        queue[tail, 0], queue[tail, 1] = a, m
        tail += 1
        queue[tail, 0], queue[tail, 1] = m, b
        tail += 1
