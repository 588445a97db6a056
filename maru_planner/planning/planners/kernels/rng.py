"""The search kernels' random numbers: a splitmix64 generator whose state (a uint64 array of one) the caller seeds,
so that a search is deterministic (numba)."""

from __future__ import annotations

import numpy as np
from numba import njit


def seed_rng(seed: int) -> np.ndarray:
    """The generator state for the search kernels' ``run`` (uint64 array of one)."""
    return np.array([seed % 2**64], dtype=np.uint64)


@njit(cache=True, inline="always")
def uniform(rng):
    """splitmix64 step → float in [0, 1)."""
    rng[0] += np.uint64(0x9E3779B97F4A7C15)
    z = rng[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)
