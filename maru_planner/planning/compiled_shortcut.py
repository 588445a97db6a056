"""Shortcut simplification of a path in one numba kernel, on the sphere checker the search ran on.

The algorithm is :func:`maru_planner.planning.postprocess.shortcut`'s: the direct start→goal edge
first, then random pairs of waypoints joined wherever the straight edge between them is free, until
``max_tries`` tries in a row fail or every pair of the path has failed (a pair that failed is not checked again:
its edge is the same). Each edge is checked by the search kernel's
:func:`~maru_planner.planning.rrtc_kernel.edge_status` (the edge's states at the motion resolution, in
bisection order, on the sphere model), so a try costs microseconds instead of a Python call into the
checker. States the spheres leave ambiguous go back to the checker's exact confirmation, as in the
search: every answer is the checker's own (``EdgeChecker.edge_valid``'s).

The kernel is resumable (:func:`run`): it returns every ``max_edges`` tries (sized so that a call lasts about 2 ms,
as the search's), so the caller can look at its deadline and the plan's cancel, and when an edge needs the exact
model (:data:`NEED_EXACT`).
Deterministic: same path, seed and scene, same result.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from numba import njit

from maru_planner.planning import rrtc_kernel as kernel
from maru_planner.planning.compiled_rrtc import next_batch
from maru_planner.planning.postprocess import drop_collinear
from maru_planner.planning.space import EdgeChecker

DONE, RUNNING, NEED_EXACT = 0, 1, 2  # what run() returns
FIRST_TRIES = 8  # tries of the first kernel call; later calls are sized to last about compiled_rrtc.CALL_SECONDS

#: Fields of the int64 shortcut state ``sc`` (index = position).
STATE_FIELDS = ("live", "failures", "first", "last", "pending", "direct_tried", "untried")
LIVE, FAILURES, FIRST, LAST, PENDING, DIRECT_TRIED, UNTRIED = range(len(STATE_FIELDS))


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
    edge_st = np.zeros(len(kernel.STATE_FIELDS), dtype=np.int64)  # edge_status's counters
    amb_states = np.empty((longest, gs.dim))
    fixed = (max_tries, sc, failed, edge_st, amb_states, kernel.seed_rng(int(seed)), edges.resolution, gs.base,
             gs.indices.astype(np.int64), *checker.kernel_inputs(), checker.confirm)  # fmt: skip
    verdict, batch = False, FIRST_TRIES
    while True:
        if check is not None:
            check()
        t_call = time.perf_counter()
        code = run(path, live, verdict, batch, *fixed)
        batch = next_batch(batch, time.perf_counter() - t_call)
        checker.check_count += int(edge_st[kernel.CHECKS])
        edge_st[kernel.CHECKS] = 0
        if code == DONE:
            break
        if code == NEED_EXACT:
            verdict = checker.first_invalid(gs.full(amb_states[: edge_st[kernel.N_AMB]])) < 0
        if time.monotonic() >= deadline:
            break
    return drop_collinear(path[live[: sc[LIVE]]])


@njit(cache=True)
def run(path, live, verdict, max_edges, max_tries, sc, failed, edge_st, amb_states, rng, resolution, base, indices, ri,
        rf, sf, grid_i, grid_f, amb, mark, shapes, confirm):  # fmt: skip
    """Try at most ``max_edges`` shortcuts of ``path[live[:sc[LIVE]]]``; DONE, RUNNING or NEED_EXACT (module doc).

    ``failed[a, b]``: the edge from waypoint a to waypoint b (indices into ``path``) is known not to be free; a pair
    drawn again counts as a failed try without being checked, and the kernel is DONE once every pair of the
    current path has failed. ``verdict``: the exact answer for the pending edge after a NEED_EXACT return (its
    ambiguous states are in ``amb_states[:edge_st[N_AMB]]``); ``ri`` … ``confirm``: the sphere checker's kernel
    inputs.
    """
    if sc[PENDING]:
        sc[PENDING] = 0
        _apply(live, sc, failed, verdict)
    robot, scene = kernel.unpack_robot(ri, rf), kernel.unpack_scene(sf)
    work = kernel.work_arrays(robot, scene)
    order, queue = kernel.edge_buffers(amb_states.shape[0])
    q = np.empty(base.shape[0])
    roots = np.empty((2, path.shape[1]))  # unused: every ambiguous state goes to the exact model (exact_near inf)
    for _ in range(max_edges):
        m = sc[LIVE]
        if sc[UNTRIED] == 0 or (sc[DIRECT_TRIED] and sc[FAILURES] >= max_tries):
            return DONE
        if sc[DIRECT_TRIED]:
            first = int(kernel.uniform(rng) * m)
            last = int(kernel.uniform(rng) * (m - 1))
            if last >= first:
                last += 1
            first, last = min(first, last), max(first, last)
            if last - first < 2 or failed[live[first], live[last]]:
                sc[FAILURES] += 1
                continue
        else:
            first, last = 0, m - 1
        sc[FIRST], sc[LAST] = first, last
        status = kernel.edge_status(path[live[first]], path[live[last]], resolution, base, indices, robot, scene,
                                    work, order, queue, q, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm,
                                    amb_states, edge_st, roots, np.inf)  # fmt: skip
        if status == kernel.AMBIGUOUS:
            sc[PENDING] = 1
            return NEED_EXACT
        _apply(live, sc, failed, status == kernel.VALID)
    return RUNNING


@njit(cache=True)
def untried_pairs(live, m, failed):
    """Pairs of the path ``live[:m]`` that skip a waypoint and have not failed."""
    count = 0
    for i in range(m):
        for j in range(i + 2, m):
            if not failed[live[i], live[j]]:
                count += 1
    return count


@njit(cache=True)
def _apply(live, sc, failed, valid):
    """The verdict on the edge ``live[sc[FIRST]] → live[sc[LAST]]``: splice the waypoints between out if valid."""
    direct = not sc[DIRECT_TRIED]
    sc[DIRECT_TRIED] = 1
    if not valid:
        failed[live[sc[FIRST]], live[sc[LAST]]] = True
        sc[UNTRIED] -= 1
        sc[FAILURES] += 0 if direct else 1
        return
    k = sc[FIRST] + 1
    for r in range(sc[LAST], sc[LIVE]):
        live[k] = live[r]
        k += 1
    sc[LIVE] = k
    sc[FAILURES] = 0
    sc[UNTRIED] = untried_pairs(live, k, failed)
