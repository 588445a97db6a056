"""RC-RRT's search loop as one numba kernel over the sphere collision model (:mod:`maru_planner.planning.rc_rrt`
runs it on a sphere checker with numba kernels; its module doc describes the algorithm).

The same steps as the Python loop, in compiled code: goal-biased samples, the modified nearest
neighbour (the ``candidates`` nearest nodes with untried inputs, brute force over the node array,
each accepted with probability 1 − σ), the best untried input toward the sample, the edge to its
lattice successor checked by :func:`~maru_planner.collision.kernels.edge_validity.edge_status` (the states of
``space.edge_states`` in bisection order, as the checker answers them), EXPANDED bookkeeping,
σ raised along the ancestors on a collision, and the straight edge to the goal from every new node
within ``goal_range``. Lattice points are found through an open-addressing hash table of the nodes'
integer coordinates (steps from the start along each axis), so no lattice size limits the search.

Resumable like :mod:`~maru_planner.planning.planners.kernels.rrtc`: :func:`run` returns

* every ``max_edges`` edge checks (:data:`RUNNING`), for the caller's termination condition;
* :data:`FULL` when the node arrays are full (:meth:`Tree.grow`);
* :data:`NEED_EXACT` when the pending edge's only doubtful states are ambiguous on the spheres (the
  checker confirms them on the exact model): they are in ``amb_states[:edge_st[edge_validity.N_AMB]]``, the caller
  passes the edge's verdict to the next call;
* :data:`SOLVED` (the goal node is ``st[GOAL_NODE]``, its branch the path) or :data:`EXHAUSTED` (no node has an untried
  input: no path at this resolution).

Deterministic: samples and acceptance draws come from the splitmix64 generator ``rng`` the caller seeds.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.kernels.edge_validity import edge_buffers, edge_status, new_counters
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, VALID
from maru_planner.collision.kernels.state_validity import work_arrays
from maru_planner.planning.planners.kernels.rng import uniform

SOLVED, RUNNING, NEED_EXACT, FULL, EXHAUSTED = 0, 1, 2, 3, 4  # what run() returns
EXTEND, GOAL_EDGE = 0, 1  # the pending edge: an input's, or a new node's straight edge to the goal

#: Fields of the int64 search state ``st`` (index = position).
STATE_FIELDS = ("count", "goal_node", "pending", "kind", "from", "input", "collisions")
COUNT, GOAL_NODE, PENDING, KIND, FROM, INPUT, COLLISIONS = range(len(STATE_FIELDS))
NO_EDGE, PROPOSED, AWAITING_VERDICT = 0, 1, 2  # st[PENDING]
GOAL_BIAS, STEP, GOAL_RANGE = range(3)  # fields of the float settings array (settings())
_EMPTY = -1  # a free slot of the hash table


class Tree:
    """The search's node arrays (``capacity`` rows), lattice hash table and state ``st``, the start in row 0."""

    def __init__(self, start: np.ndarray, capacity: int):
        dim = len(start)
        self.X = np.zeros((capacity, dim))
        self.coords = np.zeros((capacity, dim), dtype=np.int64)
        self.parent = np.full(capacity, -1, dtype=np.int64)
        self.expanded = np.zeros((capacity, 2 * dim), dtype=np.bool_)
        self.sigma = np.zeros(capacity)
        self.active = np.zeros(capacity, dtype=np.bool_)
        self.table = np.full(_table_size(capacity), _EMPTY, dtype=np.int64)
        self.st = np.zeros(len(STATE_FIELDS), dtype=np.int64)
        self.st[GOAL_NODE] = -1
        self.X[0] = start
        self.edge_st = new_counters()  # checks and ambiguous states of the last edge, where edge_status counts them

    @property
    def arrays(self) -> tuple:
        return self.X, self.coords, self.parent, self.expanded, self.sigma, self.active, self.table

    def grow(self) -> None:
        """Twice the capacity, contents kept (the hash table is rebuilt at its new size). Only a search still running
        grows: there is no goal node yet, every node is a lattice point."""
        cap = len(self.X)
        for name in ("X", "coords", "parent", "expanded", "sigma", "active"):
            old = getattr(self, name)
            new = np.full((2 * cap,) + old.shape[1:], -1 if name == "parent" else 0, dtype=old.dtype)
            new[:cap] = old
            setattr(self, name, new)
        self.table = np.full(_table_size(2 * cap), _EMPTY, dtype=np.int64)
        rehash(self.coords, self.st[COUNT], self.table)


def _table_size(capacity: int) -> int:
    """Hash table slots for ``capacity`` nodes: a power of two (the probe masks with it), at most a quarter full."""
    return 1 << max(2, int(4 * capacity - 1).bit_length())


def settings(goal_bias: float, step: float, goal_range: float) -> np.ndarray:
    """The kernel's float settings (:data:`GOAL_BIAS`, :data:`STEP`, :data:`GOAL_RANGE`)."""
    return np.array([goal_bias, step, goal_range])


@njit(cache=True, inline="always")
def _hash(coords, i, axis, delta):
    """Hash of node ``i``'s coordinates with ``delta`` added along ``axis`` (splitmix64 finaliser over a fold)."""
    h = np.uint64(0x9E3779B97F4A7C15)
    for a in range(coords.shape[1]):
        v = coords[i, a] + (delta if a == axis else 0)
        h = (h ^ np.uint64(v & 0xFFFFFFFFFFFF)) * np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(31)
    return h


@njit(cache=True, inline="always")
def _same(coords, j, i, axis, delta):
    for a in range(coords.shape[1]):
        if coords[j, a] != coords[i, a] + (delta if a == axis else 0):
            return False
    return True


@njit(cache=True)
def _lookup(coords, table, i, axis, delta):
    """The node at node ``i``'s lattice point moved by ``delta`` along ``axis`` (-1: none)."""
    mask = table.shape[0] - 1
    slot = np.int64(_hash(coords, i, axis, delta) & np.uint64(mask))
    while table[slot] != _EMPTY:
        if _same(coords, table[slot], i, axis, delta):
            return table[slot]
        slot = (slot + 1) & mask
    return -1


@njit(cache=True)
def _insert(coords, table, i):
    mask = table.shape[0] - 1
    slot = np.int64(_hash(coords, i, -1, 0) & np.uint64(mask))
    while table[slot] != _EMPTY:
        slot = (slot + 1) & mask
    table[slot] = i


@njit(cache=True)
def rehash(coords, count, table):
    """Insert nodes ``0..count-1`` into an empty ``table``."""
    for i in range(count):
        _insert(coords, table, i)


@njit(cache=True)
def _spend(expanded, active, i, u):
    expanded[i, u] = True
    for v in range(expanded.shape[1]):
        if not expanded[i, v]:
            return
    active[i] = False


@njit(cache=True)
def _add_node(X, coords, parent, expanded, active, table, st, x, i_from, u, lower, upper, step):
    """Node for lattice point ``x``, reached from ``i_from`` by input ``u``; its inputs leaving the limits or
    reaching a lattice point already in the tree are spent (and the neighbour's input back to it). Its σ is the
    fresh row's 0."""
    i = st[COUNT]
    st[COUNT] = i + 1
    X[i] = x
    parent[i] = i_from
    dim = X.shape[1]
    if i_from >= 0:
        coords[i] = coords[i_from]
        coords[i, u >> 1] += 1 if u % 2 == 0 else -1
    _insert(coords, table, i)
    untried = 0
    for a in range(dim):
        expanded[i, 2 * a] = x[a] + step > upper[a] + 1e-9
        expanded[i, 2 * a + 1] = x[a] - step < lower[a] - 1e-9
    for v in range(2 * dim):
        if expanded[i, v]:
            continue
        j = _lookup(coords, table, i, v >> 1, 1 if v % 2 == 0 else -1)
        if j >= 0:
            expanded[i, v] = True
            if not expanded[j, v ^ 1]:
                _spend(expanded, active, j, v ^ 1)
        else:
            untried += 1
    active[i] = untried > 0
    return i


@njit(cache=True)
def _raise_sigma(sigma, parent, i, m):
    inc = 1.0 / m
    while i >= 0 and inc > 1e-9:
        sigma[i] = min(1.0, sigma[i] + inc)
        inc /= m
        i = parent[i]


@njit(cache=True)
def _select(X, sigma, active, count, target, k, rng, best_i, best_d):
    """Modified NEAREST_NEIGHBOR: of the ``k`` nearest active nodes (L2), nearest first, the first accepted with
    probability 1 − σ, else the nearest; -1 when no node is active."""
    found = 0
    dim = X.shape[1]
    for i in range(count):
        if not active[i]:
            continue
        d = 0.0
        for a in range(dim):
            e = X[i, a] - target[a]
            d += e * e
        if found == k and d >= best_d[k - 1]:
            continue
        pos = min(found, k - 1)
        while pos > 0 and best_d[pos - 1] > d:
            best_d[pos], best_i[pos] = best_d[pos - 1], best_i[pos - 1]
            pos -= 1
        best_d[pos], best_i[pos] = d, i
        found = min(found + 1, k)
    if found == 0:
        return -1
    for c in range(found):
        if uniform(rng) > sigma[best_i[c]]:
            return best_i[c]
    return best_i[0]


@njit(cache=True)
def _best_input(X, expanded, i, target):
    """Untried input of node ``i`` whose successor is closest to ``target`` (the first on a tie)."""
    best, best_score = -1, -np.inf
    for v in range(expanded.shape[1]):
        if expanded[i, v]:
            continue
        diff = target[v >> 1] - X[i, v >> 1]
        score = diff if v % 2 == 0 else -diff
        if best < 0 or score > best_score:
            best, best_score = v, score
    return best


@njit(cache=True)
def _near_goal(x, goal, goal_range):
    for a in range(x.shape[0]):
        if abs(goal[a] - x[a]) > goal_range:
            return False
    return True


@njit(cache=True)
def _apply(X, coords, parent, expanded, sigma, active, table, st, x_new, valid, goal, lower, upper, step,
           goal_range):  # fmt: skip
    """The verdict on the pending edge; SOLVED, or RUNNING with the next edge to check (st[KIND] GOAL_EDGE from
    a new node near the goal) or none (st[PENDING] 0)."""
    kind, i_from = st[KIND], st[FROM]
    st[PENDING] = NO_EDGE
    if kind == GOAL_EDGE:
        if valid:
            st[GOAL_NODE] = _add_goal(X, parent, expanded, active, st, goal, i_from)
            return SOLVED
        return RUNNING
    if not valid:
        st[COLLISIONS] += 1
        _raise_sigma(sigma, parent, i_from, expanded.shape[1])
        return RUNNING
    new = _add_node(X, coords, parent, expanded, active, table, st, x_new, i_from, st[INPUT], lower, upper, step)
    if _near_goal(X[new], goal, goal_range):
        st[PENDING], st[KIND], st[FROM] = PROPOSED, GOAL_EDGE, new
    return RUNNING


@njit(cache=True)
def _add_goal(X, parent, expanded, active, st, goal, i_from):
    """The goal node (off the lattice, never extended nor hashed) as ``i_from``'s child."""
    i = st[COUNT]
    st[COUNT] = i + 1
    X[i] = goal
    parent[i] = i_from
    expanded[i, :] = True
    active[i] = False
    return i


@njit(cache=True)
def start(X, coords, parent, expanded, sigma, active, table, st, goal, lower, upper, conf):
    """Put the start (``X[0]``) in the tree; its straight edge to the goal is the first to check when in range."""
    _add_node(X, coords, parent, expanded, active, table, st, X[0], -1, 0, lower, upper, conf[STEP])
    if _near_goal(X[0], goal, conf[GOAL_RANGE]):
        st[PENDING], st[KIND], st[FROM] = PROPOSED, GOAL_EDGE, 0


@njit(cache=True)
def run(X, coords, parent, expanded, sigma, active, table, st, verdict, max_edges, edge_st, goal, x_new, amb_states,
        conf, lower, upper, rng, candidates, resolution, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes,
        confirm):  # fmt: skip
    """Advance the search by at most ``max_edges`` edge checks (module doc). ``verdict``: the exact answer for the
    pending edge after a NEED_EXACT return. ``edge_st``: where the edge checks count their checks and ambiguous
    states (:attr:`Tree.edge_st`). ``conf``: :func:`settings`; ``ri`` … ``shapes``: the sphere checker's kernel
    inputs; ``confirm``: whether it decides ambiguous states on the exact model (else they collide)."""
    goal_bias, step, goal_range = conf[GOAL_BIAS], conf[STEP], conf[GOAL_RANGE]
    if st[PENDING] == AWAITING_VERDICT:  # the caller decided the pending edge's ambiguous states
        if _apply(X, coords, parent, expanded, sigma, active, table, st, x_new, verdict, goal, lower, upper, step,
                  goal_range) == SOLVED:  # fmt: skip
            return SOLVED
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    work = work_arrays(robot, scene)
    order, queue = edge_buffers(int(np.ceil(max(step, goal_range) / resolution)) + 1)
    q = np.empty(base.shape[0])
    roots = np.empty((2, X.shape[1]))
    roots[0], roots[1] = X[0], goal
    target = np.empty(X.shape[1])
    best_i, best_d = np.empty(candidates, dtype=np.int64), np.empty(candidates)
    cap = X.shape[0]
    for _ in range(max_edges):
        if st[COUNT] + 2 > cap:  # room for a new node and the goal
            return FULL
        if st[PENDING] == NO_EDGE:
            if uniform(rng) < goal_bias:
                target[:] = goal
            else:
                for a in range(target.shape[0]):
                    target[a] = lower[a] + uniform(rng) * (upper[a] - lower[a])
            near = _select(X, sigma, active, st[COUNT], target, candidates, rng, best_i, best_d)
            if near < 0:
                return EXHAUSTED
            u = _best_input(X, expanded, near, target)
            _spend(expanded, active, near, u)
            x_new[:] = X[near]
            x_new[u >> 1] += step if u % 2 == 0 else -step
            st[PENDING], st[KIND], st[FROM], st[INPUT] = PROPOSED, EXTEND, near, u
        edge_end = x_new if st[KIND] == EXTEND else goal
        status = edge_status(X[st[FROM]], edge_end, resolution, base, indices, robot, scene, work, order, queue, q,
                             ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states, edge_st, roots,
                             np.inf)  # fmt: skip
        if status == AMBIGUOUS:
            st[PENDING] = AWAITING_VERDICT
            return NEED_EXACT
        if _apply(X, coords, parent, expanded, sigma, active, table, st, x_new, status == VALID, goal, lower, upper,
                  step, goal_range) == SOLVED:  # fmt: skip
            return SOLVED
    return RUNNING
