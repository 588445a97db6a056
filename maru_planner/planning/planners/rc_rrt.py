"""RC-RRT: Cheng & LaValle's resolution-complete RRT (ICRA 2002) as an ``ompl.base.Planner``.

Faithful to the paper's ingredients (table in docs/planning.md):

* **Discrete inputs.** Each node has ``m = 2·dim`` extension inputs: move one joint by ±``step``.
  All nodes therefore lie on the lattice ``start + step·Z^dim`` clipped to the joint limits, a
  finite set; this is where resolution completeness comes from.
* **EXPANDED bookkeeping.** ``expanded[x, u]`` is set once input u was tried from node x, so an
  input is never applied twice from the same node. Inputs leading outside the limits, or to a
  lattice point already in the tree, are marked expanded when found (they can add nothing).
* **Constraint-violation frequency σ(x).** When input u from x collides, σ(x) += 1/m, its parent's
  σ += 1/m², the grandparent's 1/m³ … (clipped to 1): regions that keep colliding are avoided.
* **Modified NEAREST_NEIGHBOR.** Only nodes with untried inputs are candidates; the ``candidates``
  nearest are visited in order and x is accepted with probability 1 − σ(x) (draw r, accept if
  r > σ(x)); if none is accepted, the nearest candidate is taken.
* **Goal bias.** With probability ``goal_bias`` the sample is the goal. The best untried input
  toward the sample is applied (the one whose successor is closest to it).
* When a new node lies within ``goal_range`` (L∞, radians) of the goal, the straight edge to the
  goal is checked; a free edge ends the search.

If every node runs out of inputs the lattice reachable from the start has been exhausted: the
planner returns INFEASIBLE ("no path at this resolution") — the resolution-complete guarantee.

Nearest neighbours come from a k-d tree (:mod:`maru_planner.planning.kdtree`). Edges are checked
through an :class:`~maru_planner.planning.space.EdgeChecker` (one batched call per edge) when
given, else through the SpaceInformation's motion validator.

On a sphere checker with numba kernels the whole loop runs compiled instead
(:mod:`maru_planner.planning.planners.kernels.rcrrt`: the same steps, brute-force nearest neighbours, a
splitmix64 sampler), leaving it about every 2 ms for the termination condition and for states the
spheres leave to the exact model. Same seed, same path on either loop, but not the same path on both.

``getPlannerData`` works when called from Python (``planner.getPlannerData(data)``); OMPL 2.0.1's
nanobind trampoline cannot pass a ``PlannerData&`` from C++ to Python, so do not go through
``SimpleSetup.getPlannerData`` for this planner.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from maru_planner.params import ParamSpec
from maru_planner.planning.checkers import is_compiled_sphere_checker
from maru_planner.planning.kdtree import GrowingKDTree
from maru_planner.planning.planners.planner_params import (
    MAX_JOINT_DISTANCE,
    MAX_NEIGHBOURS,
    SAMPLER_SEED,
    PlannerParams,
    stored_params,
)
from maru_planner.planning.planners.registry import ArmPlannerSpec, register
from maru_planner.planning.space import EdgeChecker

RCRRT_PARAMS: dict[str, ParamSpec] = {
    spec.name: spec
    for spec in (
        ParamSpec("step", 0.3, "lattice step: each input moves one joint by +-step (rad)", lower=1e-6, upper=np.pi),
        ParamSpec("goal_bias", 0.1, "probability of sampling the goal", lower=0.0, upper=1.0),
        ParamSpec(
            "candidates", 8, "nearest nodes with untried inputs visited per sample", lower=1, upper=MAX_NEIGHBOURS
        ),
        ParamSpec(
            "goal_range",
            1.5,
            "L-inf distance (rad) within which the straight edge to the goal is tried",
            lower=0.0,
            upper=MAX_JOINT_DISTANCE,
        ),
        SAMPLER_SEED,
    )
}

_SAMPLE_BATCH = 512
COMPILED_CAPACITY = 1024  # initial nodes of the compiled loop's arrays; doubled when full


class RCRRT(ob.Planner):
    """Resolution-complete RRT (see module doc). Parameters (``params()``): see ``RCRRT_PARAMS``."""

    def __init__(self, si, edge_checker=None, name: str = "RCRRT"):
        super().__init__(si, name)
        self._si = si
        self._edges = edge_checker
        self._params, self._values = stored_params(name, RCRRT_PARAMS)
        self._seed_rng = ou.RNG()
        self.exhausted = False
        self.collisions = 0
        self._reset_tree(si.getStateDimension())

    def params(self) -> PlannerParams:
        """The declared parameters, as OMPL's ``Planner::params()`` (see :mod:`.planner_params`)."""
        return self._params

    # --- hooks the MotionPlanner facade reads (maru_planner.planning.planners.registry) ----------------
    def graph_size(self) -> tuple[int, int]:
        """(nodes, edges) of the tree, read from the planner's arrays (no PlannerData copy)."""
        return int(self.count), max(0, int(self.count) - 1)

    def failure_proof(self) -> str | None:
        """Why no path exists, when the last solve exhausted the lattice; else None."""
        if not self.exhausted:
            return None
        return (
            f"RCRRT tried every input of all {self.count} lattice nodes: no path exists at "
            f"step {self._values['step']} rad"
        )

    # --- OMPL planner interface ------------------------------------------------------------
    def clear(self) -> None:
        self._reset_tree(self.dim)
        self.exhausted = False
        self.collisions = 0

    def solve(self, ptc: ob.PlannerTerminationCondition) -> ob.PlannerStatus:
        space = self._si.getStateSpace()
        self.dim = dim = space.getDimension()
        bounds = space.getBounds()
        self.lower = np.array([bounds.low[i] for i in range(dim)])
        self.upper = np.array([bounds.high[i] for i in range(dim)])
        pis = self.getPlannerInputStates()
        start_state = pis.nextStart()
        goal_state = pis.nextGoal()
        if start_state is None or goal_state is None:
            missing = ob.PlannerStatus.INVALID_START if start_state is None else ob.PlannerStatus.INVALID_GOAL
            return ob.PlannerStatus(missing)
        start = np.array([start_state[i] for i in range(dim)])
        goal = np.array([goal_state[i] for i in range(dim)])
        if self.compiled:
            return self._search_compiled(start, goal, ptc)
        return self._search(start, goal, ptc)

    @property
    def compiled(self) -> bool:
        """Whether solve() runs the compiled loop (a sphere checker with numba kernels; module doc)."""
        return self._edges is not None and is_compiled_sphere_checker(self._edges.checker)

    def getPlannerData(self, data: ob.PlannerData) -> None:  # noqa: N802 (OMPL's name)
        """Tree vertices (start tagged as start, goal as goal) and parent→child edges."""
        # PlannerData keeps pointers to the states: they must outlive it (owned by the planner).
        self._data_states = [self._ompl_state(self.X[i]) for i in range(self.count)]
        ids = []
        for i in range(self.count):
            v = ob.PlannerDataVertex(self._data_states[i])
            if i == 0:
                ids.append(data.addStartVertex(v))
            elif self.goal_node == i:
                ids.append(data.addGoalVertex(v))
            else:
                ids.append(data.addVertex(v))
        for i in range(1, self.count):
            data.addEdge(ids[self.parent[i]], ids[i])

    # --- tree storage ----------------------------------------------------------------------
    def _reset_tree(self, dim: int, capacity: int = 1024) -> None:
        self.dim = dim
        m = 2 * dim
        self.X = np.zeros((capacity, dim))
        self.parent = np.full(capacity, -1, dtype=int)
        self.expanded = np.zeros((capacity, m), dtype=bool)
        self.untried = np.zeros(capacity, dtype=int)
        self.sigma = np.zeros(capacity)
        self.active = np.zeros(capacity, dtype=bool)
        self.lattice: dict[int, int] = {}
        self.keys: list[int] = []  # lattice code of each node; -1 for the goal node (off the lattice)
        self.count = 0
        self.goal_node = -1
        self.nn = GrowingKDTree()
        self._data_states = []

    def _grow(self) -> None:
        cap = 2 * len(self.X)
        for name in ("X", "parent", "expanded", "untried", "sigma", "active"):
            old = getattr(self, name)
            new = np.zeros((cap,) + old.shape[1:], dtype=old.dtype)
            if name == "parent":
                new[:] = -1
            new[: len(old)] = old
            setattr(self, name, new)

    def _add_node(self, x: np.ndarray, key: int | None, parent: int) -> int:
        if self.count == len(self.X):
            self._grow()
        i = self.count
        self.count += 1
        self.X[i] = x
        self.parent[i] = parent
        self.keys.append(-1 if key is None else key)
        if key is None:  # the goal node: never extended
            self.expanded[i] = True
            self.untried[i] = 0
            return i
        self.lattice[key] = i
        self._mark_known_inputs(i, x, key)
        self.active[i] = self.untried[i] > 0
        return i

    def _prepare_lattice(self, start: np.ndarray) -> int:
        """Integer codes for the lattice points ``start + step·n`` inside the limits; returns the start's.

        Code = Σ (n_a − n_min_a)·stride_a (mixed radix), so a step along axis a adds ±stride_a.
        """
        step = self._step
        n_min = np.ceil((self.lower - start) / step - 1e-9).astype(int)
        n_max = np.floor((self.upper - start) / step + 1e-9).astype(int)
        strides, s = [], 1
        for a in range(self.dim):
            strides.append(s)
            s *= int(n_max[a] - n_min[a] + 1)
        self.strides = strides
        self._n_min = n_min
        return self.encode(np.zeros(self.dim, dtype=int))

    def encode(self, n) -> int:
        """Lattice code of the integer coordinates ``n`` (steps from the start along each axis)."""
        return int(sum((int(v) - int(m)) * st for v, m, st in zip(n, self._n_min, self.strides, strict=True)))

    def _mark_known_inputs(self, i: int, x: np.ndarray, key: int) -> None:
        """Inputs leaving the limits or reaching a lattice point already in the tree are spent."""
        step = self._step
        exp = self.expanded[i]
        exp[0::2] |= x + step > self.upper + 1e-9
        exp[1::2] |= x - step < self.lower - 1e-9
        lattice, strides = self.lattice, self.strides
        for u in map(int, np.flatnonzero(~exp)):
            j = lattice.get(key + strides[u >> 1] if u % 2 == 0 else key - strides[u >> 1])
            if j is not None:
                exp[u] = True
                back = u ^ 1
                if not self.expanded[j, back]:
                    self._spend(j, back)
        self.untried[i] = int((~exp).sum())

    def _spend(self, i: int, u: int) -> None:
        self.expanded[i, u] = True
        self.untried[i] -= 1
        if self.untried[i] <= 0:
            self.active[i] = False

    def _raise_sigma(self, i: int) -> None:
        inc = 1.0 / (2 * self.dim)
        while i >= 0 and inc > 1e-9:
            self.sigma[i] = min(1.0, self.sigma[i] + inc)
            inc /= 2 * self.dim
            i = self.parent[i]

    # --- the search ------------------------------------------------------------------------
    def _search(self, start: np.ndarray, goal: np.ndarray, ptc):
        p = self._values
        self._step = float(p["step"])
        goal_bias = float(p["goal_bias"])
        k = int(p["candidates"])
        goal_range = float(p["goal_range"])
        seed = p["seed"]
        if seed is None:
            seed = self._seed_rng.uniformInt(0, 2**31 - 2)
        rng = np.random.default_rng(int(seed))
        self._reset_tree(self.dim)
        self.exhausted = False
        root = self._add_node(start, self._prepare_lattice(start), -1)
        if self._goal_reachable(root, goal, goal_range):
            return self._finish(root, goal)
        samples = rng.uniform(self.lower, self.upper, size=(_SAMPLE_BATCH, self.dim))
        coins = rng.random(_SAMPLE_BATCH)
        cursor = 0
        while not ptc():
            if cursor == _SAMPLE_BATCH:
                samples = rng.uniform(self.lower, self.upper, size=(_SAMPLE_BATCH, self.dim))
                coins = rng.random(_SAMPLE_BATCH)
                cursor = 0
            target = goal if coins[cursor] < goal_bias else samples[cursor]
            cursor += 1
            near = self._select(target, k, rng)
            if near < 0:
                self.exhausted = True
                return ob.PlannerStatus(ob.PlannerStatus.INFEASIBLE)
            new = self._extend(near, target)
            if new >= 0 and self._goal_reachable(new, goal, goal_range):
                return self._finish(new, goal)
        return ob.PlannerStatus(ob.PlannerStatus.TIMEOUT)

    def _search_compiled(self, start: np.ndarray, goal: np.ndarray, ptc):
        """:meth:`_search` in :mod:`~.kernels.rcrrt`; the tree ends in this planner's arrays."""
        kernel = _kernel()
        # lazy: numba loads with these, and only a sphere checker (which loaded it already) gets here
        from maru_planner.collision.kernels.edge_validity import CHECKS, N_AMB
        from maru_planner.planning.planners.compiled_rrtc import FIRST_EDGES, next_batch
        from maru_planner.planning.planners.kernels.rng import seed_rng

        p, edges = self._values, self._edges
        checker, gs = edges.checker, edges.gs
        seed = p["seed"] if p["seed"] is not None else self._seed_rng.uniformInt(0, 2**31 - 2)
        conf = kernel.settings(float(p["goal_bias"]), float(p["step"]), float(p["goal_range"]))
        tree = kernel.Tree(start, COMPILED_CAPACITY)
        self.exhausted = False
        longest = max(float(p["step"]), min(float(p["goal_range"]), float(np.max(self.upper - self.lower))))
        amb_states = np.empty((int(np.ceil(longest / edges.resolution)) + 2, self.dim))
        kernel.start(*tree.arrays, tree.st, goal, self.lower, self.upper, conf)
        fixed = (goal, np.empty(self.dim), amb_states, conf, self.lower, self.upper, seed_rng(int(seed)),
                 int(p["candidates"]), edges.resolution, gs.base, gs.indices.astype(np.int64),
                 *checker.kernel_inputs(), checker.confirm)  # fmt: skip
        verdict, batch, code = False, FIRST_EDGES, kernel.RUNNING
        while code != kernel.SOLVED and code != kernel.EXHAUSTED and not ptc():
            t_call = time.perf_counter()
            code = kernel.run(*tree.arrays, tree.st, verdict, batch, tree.edge_st, *fixed)
            checker.check_count += int(tree.edge_st[CHECKS])
            tree.edge_st[CHECKS] = 0
            if code == kernel.NEED_EXACT:
                verdict = checker.first_invalid(gs.full(amb_states[: tree.edge_st[N_AMB]])) < 0
            elif code == kernel.FULL:
                tree.grow()
            batch = next_batch(batch, time.perf_counter() - t_call)
        self._keep_tree(tree)
        if code == kernel.EXHAUSTED:
            self.exhausted = True
            return ob.PlannerStatus(ob.PlannerStatus.INFEASIBLE)
        if code != kernel.SOLVED:
            return ob.PlannerStatus(ob.PlannerStatus.TIMEOUT)
        return self._finish_path()

    def _keep_tree(self, tree) -> None:
        """The compiled search's tree as this planner's (graph_size, getPlannerData)."""
        kernel = _kernel()
        self._reset_tree(self.dim)  # the Python loop's lattice dictionary and k-d tree stay empty
        self.count = int(tree.st[kernel.COUNT])
        self.X, self.parent, self.sigma = tree.X, tree.parent, tree.sigma
        self.expanded, self.active = tree.expanded, tree.active
        self.untried = (~tree.expanded).sum(axis=1)
        self.goal_node = int(tree.st[kernel.GOAL_NODE])
        self.collisions = int(tree.st[kernel.COLLISIONS])

    def _select(self, target: np.ndarray, k: int, rng) -> int:
        """Modified NEAREST_NEIGHBOR: nearest nodes with untried inputs, accepted w.p. 1 − σ."""
        cands = self.nn.query(target, k, self.X, self.active, self.count)
        if len(cands) == 0:
            return -1
        draws = rng.random(len(cands))
        accepted = np.flatnonzero(draws > self.sigma[cands])
        return int(cands[accepted[0]] if len(accepted) else cands[0])

    def best_input(self, i: int, target: np.ndarray) -> int:
        """Untried input of node i whose successor is closest to ``target``."""
        diff = target - self.X[i]
        score = np.empty(2 * self.dim)
        score[0::2] = diff
        score[1::2] = -diff
        score[self.expanded[i]] = -np.inf
        return int(np.argmax(score))

    def _extend(self, i: int, target: np.ndarray) -> int:
        u = self.best_input(i, target)
        self._spend(i, u)
        axis, sign = u >> 1, (1 if u % 2 == 0 else -1)
        x = self.X[i].copy()
        x[axis] += sign * self._step
        key = self.keys[i] + sign * self.strides[axis]
        if not self._edge_valid(self.X[i], x):
            self.collisions += 1
            self._raise_sigma(i)
            return -1
        return self._add_node(x, key, i)

    def _goal_reachable(self, i: int, goal: np.ndarray, goal_range: float) -> bool:
        x = self.X[i]
        if np.abs(goal - x).max() > goal_range:
            return False
        return self._edge_valid(x, goal)

    def _finish(self, i: int, goal: np.ndarray):
        self.goal_node = self._add_node(goal, None, i)
        return self._finish_path()

    def _finish_path(self):
        """The branch from the start to ``goal_node`` as the problem's solution (either loop's tree)."""
        chain = []
        j = self.goal_node
        while j >= 0:
            chain.append(j)
            j = self.parent[j]
        path = og.PathGeometric(self._si)
        for j in reversed(chain):
            path.append(self._ompl_state(self.X[j]))
        self.getProblemDefinition().addSolutionPath(path, False, 0.0, self.getName())
        return ob.PlannerStatus(ob.PlannerStatus.EXACT_SOLUTION)

    def _edge_valid(self, a: np.ndarray, b: np.ndarray) -> bool:
        if self._edges is not None:
            return self._edges.edge_valid(a, b)
        return bool(self._si.checkMotion(self._ompl_state(a), self._ompl_state(b)))

    def _ompl_state(self, x: np.ndarray):
        s = self._si.allocState()
        for d in range(self.dim):
            s[d] = float(x[d])
        return s


def _kernel():
    """The compiled loop's module: imported on first use (numba loads with it; exact-only callers never need it)."""
    # lazy: numba, only once a sphere checker loaded it
    from maru_planner.planning.planners.kernels import rcrrt as rcrrt_kernel

    return rcrrt_kernel


def _build(si: ob.SpaceInformation, params: dict[str, Any], edge_checker: EdgeChecker | None) -> RCRRT:
    planner = RCRRT(si, edge_checker)
    planner.params().set_params(params)
    return planner


register(
    ArmPlannerSpec(
        "RCRRT",
        "resolution-complete RRT (Cheng & LaValle 2002) on a joint lattice",
        _build,
        RCRRT_PARAMS,
        frozenset({"tree", "resolution_complete"}),
    )
)
