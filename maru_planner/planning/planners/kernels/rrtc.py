"""RRT-Connect as one numba kernel over the sphere collision model (the ideas of VAMP, in Python).

The whole search loop runs compiled: two trees in preallocated arrays, brute-force nearest
neighbours over each tree's contiguous node array, extend/connect steps of at most ``range``
(L2, like OMPL's RRTConnect), VAMP's balanced trees and dynamic domains (:func:`tuning`: the
smaller tree extends while the other has twice its nodes; a node whose extension failed only
takes samples within its domain), and every edge checked by
:func:`maru_planner.collision.kernels.edge_validity.edge_status`: at the motion resolution (the states of
:func:`maru_planner.planning.space.edge_states`, computed the same way) in coarse-to-fine bisection order with an
early exit on the first colliding state, each state answered as the sphere checker's ``classify_state`` does.

The search is a resumable state machine (``st``, :data:`STATE_FIELDS`): :func:`run` proposes one
edge at a time and applies its verdict, and returns to the caller

* every ``max_edges`` edges (:data:`RUNNING`), so the caller can evaluate OMPL's termination
  condition;
* when a tree's arrays are full (:data:`FULL`): the caller grows them and calls again;
* when some of the edge's states are only *ambiguous* on the sphere model (outer spheres touch, no
  inner ball does), lie within ``exact_near`` of the start or goal, and ``confirm`` is set
  (:data:`NEED_EXACT`): those states are in ``amb_states[:st[N_AMB]]``, the caller decides them on
  the exact model and passes the edge's verdict to the next call;
* with a solution (:data:`SOLVED`): :func:`solution_path`.

Deterministic: the samples come from a splitmix64 generator whose state (``rng``, :func:`seed_rng`) the caller seeds.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.kernels import edge_validity
from maru_planner.collision.kernels.edge_validity import edge_buffers, edge_status
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, VALID
from maru_planner.collision.kernels.state_validity import work_arrays
from maru_planner.planning.planners.kernels.rng import seed_rng as seed_rng  # the generator state run() takes
from maru_planner.planning.planners.kernels.rng import uniform

SOLVED, RUNNING, NEED_EXACT, FULL = 0, 1, 2, 3  # what run() returns
BALANCE, DOMAIN_RADIUS, DOMAIN_ALPHA, DOMAIN_MIN_RADIUS = range(4)  # fields of the tuning array (tuning())
DIRECT, EXTEND, CONNECT = 0, 1, 2  # phases: the straight start-goal edge, extend toward a sample, connect

#: Fields of the int64 search state ``st`` (index = position).
STATE_FIELDS = ("phase", "tree", "from", "target", "pending", "reached", "n0", "n1", "checks", "n_amb",
                "link0", "link1", "duplicate")  # fmt: skip
(PHASE, TREE, FROM, TARGET, PENDING, REACHED, N0, N1, CHECKS, N_AMB, LINK0, LINK1, DUPLICATE) = range(len(STATE_FIELDS))
# edge_status counts the edge's checks and ambiguous states in ``st`` itself
assert (CHECKS, N_AMB) == (edge_validity.CHECKS, edge_validity.N_AMB)


def new_state(
    start: np.ndarray, goal: np.ndarray, capacity: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Trees (2, capacity, dim) holding the start (tree 0) and the goal (tree 1), parents, domain radii, ``st``."""
    dim = len(start)
    nodes = np.zeros((2, capacity, dim))
    nodes[0, 0], nodes[1, 0] = start, goal
    parent = np.full((2, capacity), -1, dtype=np.int64)
    radius = np.full((2, capacity), np.inf)
    st = np.zeros(len(STATE_FIELDS), dtype=np.int64)
    st[N0] = st[N1] = 1
    st[PHASE] = DIRECT
    return nodes, parent, radius, st


def grow(nodes: np.ndarray, parent: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The trees' arrays with twice the capacity (contents kept)."""
    cap = nodes.shape[1]
    bigger = np.zeros((2, 2 * cap, nodes.shape[2]))
    bigger[:, :cap] = nodes
    parents = np.full((2, 2 * cap), -1, dtype=np.int64)
    parents[:, :cap] = parent
    radii = np.full((2, 2 * cap), np.inf)
    radii[:, :cap] = radius
    return bigger, parents, radii


def tuning(balance: bool, domain_radius: float, domain_alpha: float, domain_min_radius: float) -> np.ndarray:
    """The kernel's tree balancing and dynamic-domain settings (:func:`run`); ``domain_radius`` 0 = no domains."""
    return np.array([float(balance), domain_radius, domain_alpha, domain_min_radius])


@njit(cache=True)
def _nearest(tree_nodes, count, q):
    return _nearest_with_distance(tree_nodes, count, q)[0]


@njit(cache=True)
def _nearest_with_distance(tree_nodes, count, q):
    """(index, L2 distance) of the node of ``tree_nodes[:count]`` nearest ``q``."""
    best, best_d = 0, np.inf
    dim = q.shape[0]
    for i in range(count):
        d = 0.0
        for a in range(dim):
            e = tree_nodes[i, a] - q[a]
            d += e * e
        if d < best_d:
            best, best_d = i, d
    return best, np.sqrt(best_d)


@njit(cache=True)
def _steer(q_from, q_to, max_range, out):
    """Write into ``out`` the point at most ``max_range`` (L2) from ``q_from`` toward ``q_to``; True if it is q_to."""
    dim = q_from.shape[0]
    dist = 0.0
    for a in range(dim):
        e = q_to[a] - q_from[a]
        dist += e * e
    dist = np.sqrt(dist)
    if dist <= max_range:
        out[:] = q_to
        return True
    f = max_range / dist
    for a in range(dim):
        out[a] = q_from[a] + f * (q_to[a] - q_from[a])
    return False


@njit(cache=True)
def _add(nodes, parent, st, tree, q, par):
    field = N0 + tree
    i = st[field]
    nodes[tree, i] = q
    parent[tree, i] = par
    st[field] = i + 1
    return i


@njit(cache=True)
def _solved(st, tree, node, other):
    """The trees meet: ``node`` of ``tree`` and ``other`` of the other tree."""
    st[LINK0 + tree] = node
    st[LINK0 + 1 - tree] = other
    return SOLVED


@njit(cache=True)
def propose(nodes, radius, st, q_new, lower, upper, rng, max_range):
    """The next edge: from node st[FROM] of tree st[TREE] to ``q_new`` (st[REACHED]: q_new is the target).

    False, and no edge, when an extension's sample lies outside its nearest node's dynamic domain (``radius``).
    """
    phase, tree = st[PHASE], st[TREE]
    if phase == DIRECT:
        q_new[:] = nodes[1, 0]
        st[TREE], st[FROM], st[REACHED] = 0, 0, 1
        return True
    if phase == EXTEND:
        sample = np.empty(lower.shape[0])
        for a in range(lower.shape[0]):
            sample[a] = lower[a] + uniform(rng) * (upper[a] - lower[a])
        nearest, distance = _nearest_with_distance(nodes[tree], st[N0 + tree], sample)
        if distance > radius[tree, nearest]:
            return False
        st[FROM] = nearest
        st[REACHED] = _steer(nodes[tree, nearest], sample, max_range, q_new)
        return True
    st[REACHED] = _steer(nodes[tree, st[FROM]], nodes[1 - tree, st[TARGET]], max_range, q_new)
    return True


@njit(cache=True)
def next_extension(st, last, tuning):
    """The tree to extend after tree ``last``'s round: the other one (as OMPL), unless balancing keeps
    extending ``last`` while the other has at least twice its nodes (VAMP's ``balance``, ``tree_ratio`` 1)."""
    other = 1 - last
    if tuning[BALANCE] > 0.0 and st[N0 + other] >= 2 * st[N0 + last]:
        return last
    return other


@njit(cache=True)
def update_domain(radius, tree, node, valid, tuning):
    """Dynamic domain (Yershova et al. 2005, as VAMP): a node whose extension failed gets a domain of
    ``DOMAIN_RADIUS``, shrunk by ``DOMAIN_ALPHA`` at each further failure (not below ``DOMAIN_MIN_RADIUS``)
    and grown by it at each success."""
    if tuning[DOMAIN_RADIUS] <= 0.0:
        return
    r = radius[tree, node]
    if valid:
        if r < np.inf:
            radius[tree, node] = r * (1.0 + tuning[DOMAIN_ALPHA])
    elif r == np.inf:
        radius[tree, node] = tuning[DOMAIN_RADIUS]
    else:
        radius[tree, node] = max(r * (1.0 - tuning[DOMAIN_ALPHA]), tuning[DOMAIN_MIN_RADIUS])


@njit(cache=True)
def _apply(nodes, parent, radius, st, q_new, valid, tuning):
    """Update the trees and the phase with the verdict on the proposed edge; SOLVED or RUNNING."""
    phase, tree = st[PHASE], st[TREE]
    if phase == DIRECT:
        if valid:
            st[DUPLICATE] = 0
            return _solved(st, 0, 0, 0)
        st[PHASE], st[TREE] = EXTEND, 0
        return RUNNING
    if phase == EXTEND:
        update_domain(radius, tree, st[FROM], valid, tuning)
    if not valid:  # trapped: the round of the tree that extended last is over
        st[PHASE], st[TREE] = EXTEND, next_extension(st, tree if phase == EXTEND else 1 - tree, tuning)
        return RUNNING
    new = _add(nodes, parent, st, tree, q_new, st[FROM])
    radius[tree, new] = np.inf
    if phase == EXTEND:
        other = 1 - tree
        st[PHASE], st[TREE], st[TARGET] = CONNECT, other, new
        st[FROM] = _nearest(nodes[other], st[N0 + other], q_new)
        return RUNNING
    if st[REACHED]:
        st[DUPLICATE] = 1
        return _solved(st, tree, new, st[TARGET])
    st[FROM] = new
    return RUNNING


@njit(cache=True)
def run(nodes, parent, radius, verdict, max_edges, st, q_new, amb_states, tuning, lower, upper, rng, max_range,
        resolution, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, exact_near):  # fmt: skip
    """Advance the search by at most ``max_edges`` edge checks; SOLVED, RUNNING, NEED_EXACT or FULL (module doc).

    ``verdict``: the exact answer for the pending edge after a NEED_EXACT return (ignored otherwise);
    ``tuning``: :func:`tuning`; ``ri`` … ``shapes``: the sphere checker's kernel inputs; ``exact_near``: see
    :func:`~maru_planner.collision.kernels.edge_validity.check_edge`.
    """
    if st[PENDING]:
        st[PENDING] = 0
        if _apply(nodes, parent, radius, st, q_new, verdict, tuning) == SOLVED:
            return SOLVED
    cap = nodes.shape[1]
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    work = work_arrays(robot, scene)
    longest = min(max_range, np.max(upper - lower))  # an extension's edge: L∞ <= its L2 range, within the bounds
    order, queue = edge_buffers(int(np.ceil(longest / resolution)) + 1)
    q = np.empty(base.shape[0])
    for _ in range(max_edges):
        if st[N0] >= cap or st[N1] >= cap:
            return FULL
        if not propose(nodes, radius, st, q_new, lower, upper, rng, max_range):  # an iteration without an edge
            st[TREE] = next_extension(st, st[TREE], tuning)
            continue
        tree = st[TREE]
        status = edge_status(nodes[tree, st[FROM]], q_new, resolution, base, indices, robot, scene, work, order,
                             queue, q, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states, st,
                             nodes[:, 0], exact_near)  # fmt: skip
        if status == AMBIGUOUS:
            st[PENDING] = 1
            return NEED_EXACT
        if _apply(nodes, parent, radius, st, q_new, status == VALID, tuning) == SOLVED:
            return SOLVED
    return RUNNING


@njit(cache=True)
def solution_path(nodes, parent, st):
    """Waypoints start → goal of a SOLVED search: tree 0's branch to LINK0, then tree 1's from LINK1."""
    n0 = 0
    i = st[LINK0]
    while i >= 0:
        n0 += 1
        i = parent[0, i]
    first = parent[1, st[LINK1]] if st[DUPLICATE] else st[LINK1]
    n1 = 0
    i = first
    while i >= 0:
        n1 += 1
        i = parent[1, i]
    out = np.empty((n0 + n1, nodes.shape[2]))
    i, k = st[LINK0], n0 - 1
    while i >= 0:
        out[k] = nodes[0, i]
        i, k = parent[0, i], k - 1
    i, k = first, n0
    while i >= 0:
        out[k] = nodes[1, i]
        i, k = parent[1, i], k + 1
    return out
