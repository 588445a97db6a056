"""An edge on the sphere model: its states at the motion resolution, in coarse-to-fine bisection order, each
classified until the first that collides (numba).

The states are those of :func:`maru_planner.planning.space.edge_states`, computed the same way (L∞ step, the edge's
start excluded), as full configurations. Each is classified by :func:`~.state_validity.classify`, or, in a scene
large enough for the sphere checker's grid, by its own scan (:func:`~.sphere_scan.scan_nb`). States only ambiguous
on the spheres near the search's roots may go to the exact model: :func:`check_edge` lists them for the caller.

The search kernels (:mod:`maru_planner.planning.planners.kernels`) call :func:`edge_status` with their own state
array ``st``, in which it counts at :data:`CHECKS` and :data:`N_AMB`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.kernels import bisection
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, COLLIDING, VALID
from maru_planner.collision.kernels.sphere_scan import scan_nb
from maru_planner.collision.kernels.state_validity import (
    classify,
    clear_on_shapes,
    pairs_clear_on_shapes,
    work_arrays,
)

# Where edge_status counts in its caller's int64 array ``st``: the states it checked, and the ambiguous states it
# left in ``amb_states`` for the exact model. The RRT-Connect kernel's search state holds them at these places.
CHECKS, N_AMB = 8, 9
#: An edge's bisection order into work arrays (:func:`edge_buffers`), compiled here and inlined into the edge loops.
bisection_order_into = njit(cache=True, inline="always")(bisection.bisection_order_into)


def new_counters() -> np.ndarray:
    """An ``st`` array for :func:`edge_status` that holds only its counters (:data:`CHECKS`, :data:`N_AMB`)."""
    return np.zeros(N_AMB + 1, dtype=np.int64)


@njit(cache=True)
def edge_buffers(n):
    """Work arrays of :func:`bisection_order_into` for edges of up to ``n`` states: the order and a queue."""
    return np.empty(n, dtype=np.int64), np.empty((2 * n + 1, 2), dtype=np.int64)


@njit(cache=True)
def _near_roots(q, indices, roots, exact_near):
    """Whether full configuration ``q`` is within ``exact_near`` (L∞ over the group's ``indices``) of a root."""
    for r in range(2):
        far = 0.0
        for a in range(indices.shape[0]):
            far = max(far, abs(q[indices[a]] - roots[r, a]))
        if far <= exact_near:
            return True
    return False


@njit(cache=True)
def check_edge(
    qa, qb, resolution, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states, st, roots,
    exact_near,
):  # fmt: skip
    """VALID, COLLIDING or AMBIGUOUS for the edge qa → qb (qa excluded) on the sphere model.

    The edge's states, as full configurations (``base`` supplies the joints outside the group's
    ``indices``), are classified in bisection order: by :func:`~.state_validity.classify` on the sphere checker's
    packed robot and scene (``ri``/``rf``/``sf``), or, when the checker looks obstacles up in a grid
    (a large scene, ``grid_i``/``grid_f``), by its own scan (``scan_nb`` with its work arrays
    ``amb``/``mark``). COLLIDING at the first colliding state. With ``confirm``, states that are only
    ambiguous and within ``exact_near`` (L∞) of one of the ``roots`` (start, goal) are decided on the exact
    shapes: valid where GJK's bounds clear every pair near contact (:func:`~.state_validity.clear_on_shapes`,
    ``shapes``), else copied to ``amb_states`` (``st[N_AMB]`` of them) for coal, with every later one (coal is asked
    anyway, and most such states are contacts: GJK's time would be lost), and the edge is AMBIGUOUS if no state
    collides; other ambiguous states collide (the pure, conservative sphere model, everywhere without ``confirm``).
    """
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    order, queue = edge_buffers(1)
    return edge_status(qa, qb, resolution, base, indices, robot, scene, work_arrays(robot, scene), order, queue,
                       np.empty(base.shape[0]), ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states,
                       st, roots, exact_near)  # fmt: skip


@njit(cache=True)
def edge_status(qa, qb, resolution, base, indices, robot, scene, work, order, queue, q, ri, rf, sf, grid_i, grid_f,
                amb, mark, shapes, confirm, amb_states, st, roots, exact_near):  # fmt: skip
    """:func:`check_edge` on the robot and scene its caller unpacked once (the search and shortcut kernels' ``run``),
    their :func:`~.state_validity.work_arrays`, edge buffers (:func:`edge_buffers`; larger ones are made for a longer
    edge) and a configuration buffer ``q``.

    Without a grid each state is made when its turn comes: most edges of a search end at their first states.
    """
    dim = qa.shape[0]
    steps = 0.0
    for a in range(dim):
        steps = max(steps, abs(qb[a] - qa[a]))
    n = max(1, int(np.ceil(steps / resolution)))
    if order.shape[0] < n:
        order, queue = edge_buffers(n)
    bisection_order_into(n, order, queue, False)
    if grid_i[0] > 0:
        return _check_edge_by_grid(qa, qb, n, order, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes,
                                   confirm, amb_states, st, roots, exact_near, robot, scene, work)  # fmt: skip
    n_amb = 0
    for row in range(n):
        t = (order[row] + 1) / n  # the state written out as in _check_edge_by_grid: a shared helper cost 2-3 %
        q[:] = base
        for a in range(dim):
            q[indices[a]] = qa[a] + t * (qb[a] - qa[a])
        exact = confirm and _near_roots(q, indices, roots, exact_near)
        status = classify(q, robot, scene, work, not exact)
        st[CHECKS] += 1
        if status == COLLIDING or (status == AMBIGUOUS and not exact):
            return COLLIDING
        if status == AMBIGUOUS and (n_amb > 0 or not clear_on_shapes(q, robot, scene, work, shapes)):
            for a in range(dim):
                amb_states[n_amb, a] = q[indices[a]]
            n_amb += 1
    st[N_AMB] = n_amb
    return AMBIGUOUS if n_amb > 0 else VALID


@njit(cache=True)
def _check_edge_by_grid(qa, qb, n, order, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm,
                        amb_states, st, roots, exact_near, robot, scene, work):  # fmt: skip
    """:func:`check_edge` of an edge of ``n`` states in ``order`` through the checker's grid scan (``scan_nb``)."""
    dim = qa.shape[0]
    states = np.empty((n, base.shape[0]))
    for r in range(n):
        t = (order[r] + 1) / n
        states[r] = base
        for a in range(dim):
            states[r, indices[a]] = qa[a] + t * (qb[a] - qa[a])
    n_amb, row = 0, 0
    while row < n:
        hit, status, n_pairs = scan_nb(states, row, ri, rf, sf, grid_i, grid_f, amb, mark, True)
        if hit < 0:
            st[CHECKS] += n - row
            break
        st[CHECKS] += hit + 1 - row
        row = hit + 1
        if status == AMBIGUOUS and not (confirm and _near_roots(states[hit], indices, roots, exact_near)):
            status = COLLIDING
        if status == COLLIDING:
            return COLLIDING
        in_doubt = amb[:n_pairs]
        if status == AMBIGUOUS and (n_amb > 0 or not pairs_clear_on_shapes(states[hit], in_doubt, robot, scene, work,
                                                                         shapes)):  # fmt: skip
            for a in range(dim):
                amb_states[n_amb, a] = states[hit, indices[a]]
            n_amb += 1
    st[N_AMB] = n_amb
    return AMBIGUOUS if n_amb > 0 else VALID
