"""Measures of a joint-space path (rad): its length and OMPL's smoothness."""

from __future__ import annotations

import math

import numpy as np


def path_length(path: np.ndarray) -> float:
    """Sum of Euclidean joint-space segment lengths (rad)."""
    if len(path) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


def smoothness(path: np.ndarray) -> float:
    """OMPL's ``PathGeometric::smoothness``: Σ (2·turn angle / (a + b))² over waypoint triples (0 = straight)."""
    path = np.asarray(path, dtype=float)
    if len(path) < 3:
        return 0.0
    a = np.linalg.norm(path[1:-1] - path[:-2], axis=1)
    b = np.linalg.norm(path[2:] - path[1:-1], axis=1)
    c = np.linalg.norm(path[2:] - path[:-2], axis=1)
    turns = (a >= 1e-12) & (b >= 1e-12)  # a repeated waypoint has no turn
    cos_value = (a * a + b * b - c * c) / np.where(turns, 2.0 * a * b, 1.0)
    turns &= (cos_value > -1.0) & (cos_value < 1.0)
    k = 2.0 * (math.pi - np.arccos(cos_value[turns])) / (a + b)[turns]
    return float(np.sum(k * k))
