"""Shortcut simplification of a path in one numba kernel, on the sphere checker the search ran on.

The algorithm is :func:`maru_planner.planning.postprocess.shortcut`'s; the loop runs compiled
(:mod:`maru_planner.planning.planners.kernels.shortcut`, whose module doc describes it), each edge checked by the
search kernels' :func:`~maru_planner.collision.kernels.edge_validity.edge_status` (the edge's states at the motion
resolution, in bisection order, on the sphere model), so a try costs microseconds instead of a Python call into the
checker. States the spheres leave ambiguous go back to the checker's exact confirmation, as in the
search: every answer is the checker's own (``EdgeChecker.edge_valid``'s).

:func:`shortcut` calls the resumable kernel every ``max_edges`` tries (sized so that a call lasts about 2 ms,
as the search's), so it can look at its deadline and the plan's cancel, and when an edge needs the exact
model (:data:`NEED_EXACT`).
Deterministic: same path, seed and scene, same result.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from maru_planner.collision.kernels.edge_validity import CHECKS, N_AMB, new_counters
from maru_planner.planning.planners.compiled_rrtc import next_batch
from maru_planner.planning.planners.kernels.rng import seed_rng
from maru_planner.planning.planners.kernels.shortcut import (
    DIRECT_TRIED,
    DONE,
    FAILURES,
    FIRST,
    LAST,
    LIVE,
    NEED_EXACT,
    PENDING,
    RUNNING,
    STATE_FIELDS,
    UNTRIED,
    run,
    untried_pairs,
)
from maru_planner.planning.space import EdgeChecker
from maru_planner.trajectory.blends import drop_collinear

__all__ = ["DIRECT_TRIED", "DONE", "FAILURES", "FIRST", "FIRST_TRIES", "LAST", "LIVE", "NEED_EXACT", "PENDING",
           "RUNNING", "STATE_FIELDS", "UNTRIED", "run", "shortcut", "untried_pairs"]  # fmt: skip

FIRST_TRIES = 8  # tries of the first kernel call; later calls are sized to last about compiled_rrtc.CALL_SECONDS


def shortcut(path: np.ndarray, edges: EdgeChecker, seed: int, deadline: float, max_tries: int,
             check: Callable[[], None] | None = None) -> np.ndarray:  # fmt: skip
    """``path`` (group configurations) shortcut on ``edges`` (a numba sphere checker's; see module doc).

    Stops after ``max_tries`` failed tries in a row, at ``deadline`` (``time.monotonic()``), or when the path is
    one edge. ``check`` is called before each batch of tries (a plan monitor's cancel raises from it).
    """
    path = drop_collinear(np.asarray(path, dtype=float))
    if len(path) <= 2:
        return path
    checker, gs = edges.checker, edges.gs
    longest = int(math.ceil(float(np.ptp(path, axis=0).max()) / edges.resolution)) + 2  # any edge's states
    live, sc = np.arange(len(path), dtype=np.int64), np.zeros(len(STATE_FIELDS), dtype=np.int64)
    sc[LIVE] = len(path)
    failed = np.zeros((len(path), len(path)), dtype=np.bool_)
    sc[UNTRIED] = untried_pairs(live, len(path), failed)
    edge_st = new_counters()  # edge_status's counters
    amb_states = np.empty((longest, gs.dim))
    fixed = (max_tries, sc, failed, edge_st, amb_states, seed_rng(int(seed)), edges.resolution, gs.base,
             gs.indices.astype(np.int64), *checker.kernel_inputs(), checker.confirm)  # fmt: skip
    verdict, batch = False, FIRST_TRIES
    while True:
        if check is not None:
            check()
        t_call = time.perf_counter()
        code = run(path, live, verdict, batch, *fixed)
        batch = next_batch(batch, time.perf_counter() - t_call)
        checker.check_count += int(edge_st[CHECKS])
        edge_st[CHECKS] = 0
        if code == DONE:
            break
        if code == NEED_EXACT:
            verdict = checker.first_invalid(gs.full(amb_states[: edge_st[N_AMB]])) < 0
        if time.monotonic() >= deadline:
            break
    return drop_collinear(path[live[: sc[LIVE]]])
