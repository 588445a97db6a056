"""Numba pieces shared by the grid searches (2-D A*/JPS and SE(2) A*): a binary heap and the clock.

The heap is three parallel arrays (key, g, node id) ordered by key, then larger g first; it grows
by doubling when full (the caller keeps the returned arrays).
"""

from __future__ import annotations

import time

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def heap_push(keys, gs, ids, size, key, g, node):
    """Push (key, g, node) into a heap of ``size`` entries: sift the hole up, then place. Returns the new size."""
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        pk = keys[parent]
        if pk < key or (pk == key and gs[parent] >= g):
            break
        keys[i] = pk
        gs[i] = gs[parent]
        ids[i] = ids[parent]
        i = parent
    keys[i] = key
    gs[i] = g
    ids[i] = node
    return size + 1


@numba.njit(cache=True, nogil=True)
def heap_pop(keys, gs, ids, size):
    """Pop the smallest entry; returns (node, g, new size)."""
    node = ids[0]
    g = gs[0]
    size -= 1
    key = keys[size]
    lg = gs[size]
    lid = ids[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        right = child + 1
        if right < size and (keys[right] < keys[child] or (keys[right] == keys[child] and gs[right] > gs[child])):
            child = right
        ck = keys[child]
        if key < ck or (key == ck and lg >= gs[child]):
            break
        keys[i] = ck
        gs[i] = gs[child]
        ids[i] = ids[child]
        i = child
    keys[i] = key
    gs[i] = lg
    ids[i] = lid
    return node, g, size


@numba.njit(cache=True, nogil=True)
def heap_grow(keys, gs, ids):
    """The heap arrays at twice their capacity (same entries)."""
    n = keys.shape[0]
    k2, g2, i2 = np.empty(2 * n), np.empty(2 * n), np.empty(2 * n, dtype=np.int64)
    k2[:n] = keys
    g2[:n] = gs
    i2[:n] = ids
    return k2, g2, i2


@numba.njit(cache=True)
def now():
    """time.perf_counter() from inside a kernel (compared with a Deadline's ``at``)."""
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t
