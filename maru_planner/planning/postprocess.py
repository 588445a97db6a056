"""Post-processing of a joint-space path: shortcut simplification (it never leaves the free space).

Every shortcut edge is checked with the same batched edge check (and resolution) as the planner's motion validator
before it replaces a sub-path. The path metrics, :func:`drop_collinear` and the trapezoidal time parameterisation
live in :mod:`maru_planner.trajectory` now (re-exported here).
"""

from __future__ import annotations

import time

import numpy as np

from maru_planner.trajectory.blends import COLLINEAR_OFFSET, drop_collinear
from maru_planner.trajectory.metrics import path_length, smoothness
from maru_planner.trajectory.trapezoid import time_parameterize

__all__ = ["COLLINEAR_OFFSET", "drop_collinear", "path_length", "shortcut", "smoothness", "time_parameterize"]


def shortcut(path: np.ndarray, edge_valid, rng: np.random.Generator, deadline: float, max_tries: int = 200):
    """Random shortcutting: join two random waypoints when the straight edge between them is free.

    ``edge_valid(qa, qb)`` is the batched motion check. The direct start→goal edge is tried first. Stops after
    ``max_tries`` failed tries in a row, at ``deadline``, or once every pair of the path has failed (a pair that
    failed is not checked again: its edge is the same). Returns (path, edge checks made).
    """
    path = drop_collinear(np.asarray(path, float))
    checks = 0
    if len(path) > 2:
        checks += 1
        if edge_valid(path[0], path[-1]):
            return path[[0, -1]], checks
    live = list(range(len(path)))  # the kept waypoints, as indices into path
    failed = {(0, len(path) - 1)}
    untried = _untried_pairs(live, failed)
    failures = 0
    while untried and failures < max_tries and time.monotonic() < deadline:
        i, j = sorted(rng.choice(len(live), size=2, replace=False))
        pair = (live[i], live[j])
        if j - i < 2 or pair in failed:
            failures += 1
            continue
        checks += 1
        if edge_valid(path[pair[0]], path[pair[1]]):
            live = live[: i + 1] + live[j:]
            untried = _untried_pairs(live, failed)
            failures = 0
        else:
            failed.add(pair)
            untried -= 1
            failures += 1
    return drop_collinear(path[live]), checks


def _untried_pairs(live: list[int], failed: set[tuple[int, int]]) -> int:
    """Pairs of the path ``live`` that skip a waypoint and have not failed."""
    m = len(live)
    return sum((live[i], live[j]) not in failed for i in range(m) for j in range(i + 2, m))
