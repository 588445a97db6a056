"""Shortcut simplification of a path as one numba kernel, on the sphere checker the search ran on
(:func:`maru_planner.planning.planners.compiled_shortcut.shortcut` runs it).

The algorithm is :func:`maru_planner.planning.postprocess.shortcut`'s: the direct start→goal edge
first, then random pairs of waypoints joined wherever the straight edge between them is free, until
``max_tries`` tries in a row fail or every pair of the path has failed (a pair that failed is not checked again:
its edge is the same). Each edge is checked by
:func:`~maru_planner.collision.kernels.edge_validity.edge_status` (the edge's states at the motion resolution, in
bisection order, on the sphere model); states the spheres leave ambiguous go back to the checker's exact
confirmation (:data:`NEED_EXACT`), as in the search.

Resumable (:func:`run`): it returns every ``max_edges`` tries, so the caller can look at its deadline and the plan's
cancel. Deterministic: same path, seed and scene, same result.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.kernels.edge_validity import edge_buffers, edge_status
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, VALID
from maru_planner.collision.kernels.state_validity import work_arrays
from maru_planner.planning.planners.kernels.rng import uniform

DONE, RUNNING, NEED_EXACT = 0, 1, 2  # what run() returns

#: Fields of the int64 shortcut state ``sc`` (index = position).
STATE_FIELDS = ("live", "failures", "first", "last", "pending", "direct_tried", "untried")
LIVE, FAILURES, FIRST, LAST, PENDING, DIRECT_TRIED, UNTRIED = range(len(STATE_FIELDS))


@njit(cache=True)
def run(path, live, verdict, max_edges, max_tries, sc, failed, edge_st, amb_states, rng, resolution, base, indices, ri,
        rf, sf, grid_i, grid_f, amb, mark, shapes, confirm):  # fmt: skip
    """Try at most ``max_edges`` shortcuts of ``path[live[:sc[LIVE]]]``; DONE, RUNNING or NEED_EXACT (module doc).

    ``failed[a, b]``: the edge from waypoint a to waypoint b (indices into ``path``) is known not to be free; a pair
    drawn again counts as a failed try without being checked, and the kernel is DONE once every pair of the
    current path has failed. ``verdict``: the exact answer for the pending edge after a NEED_EXACT return (its
    ambiguous states are in ``amb_states[:edge_st[edge_validity.N_AMB]]``); ``ri`` … ``confirm``: the sphere
    checker's kernel inputs.
    """
    if sc[PENDING]:
        sc[PENDING] = 0
        _apply(live, sc, failed, verdict)
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    work = work_arrays(robot, scene)
    order, queue = edge_buffers(amb_states.shape[0])
    q = np.empty(base.shape[0])
    roots = np.empty((2, path.shape[1]))  # unused: every ambiguous state goes to the exact model (exact_near inf)
    for _ in range(max_edges):
        m = sc[LIVE]
        if sc[UNTRIED] == 0 or (sc[DIRECT_TRIED] and sc[FAILURES] >= max_tries):
            return DONE
        if sc[DIRECT_TRIED]:
            first = int(uniform(rng) * m)
            last = int(uniform(rng) * (m - 1))
            if last >= first:
                last += 1
            first, last = min(first, last), max(first, last)
            if last - first < 2 or failed[live[first], live[last]]:
                sc[FAILURES] += 1
                continue
        else:
            first, last = 0, m - 1
        sc[FIRST], sc[LAST] = first, last
        status = edge_status(path[live[first]], path[live[last]], resolution, base, indices, robot, scene, work,
                             order, queue, q, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states,
                             edge_st, roots, np.inf)  # fmt: skip
        if status == AMBIGUOUS:
            sc[PENDING] = 1
            return NEED_EXACT
        _apply(live, sc, failed, status == VALID)
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
