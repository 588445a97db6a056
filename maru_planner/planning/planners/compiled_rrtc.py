"""CompiledRRTConnect: RRT-Connect whose whole search loop runs in one numba kernel, as an ``ompl.base.Planner``.

The search (:mod:`maru_planner.planning.planners.kernels.rrtc`) plans on the sphere model of a
:class:`~maru_planner.collision.SphereCollisionChecker`: trees, nearest neighbours, extend/connect
and edge checks at the facade's motion resolution never leave compiled code, except

* about every 2 ms, to evaluate OMPL's termination condition;
* for an edge whose states the spheres leave ambiguous (outer spheres touch, no inner ball does):
  when the checker confirms on the exact model (``confirm=True``, its default), those states go to
  ``checker.first_invalid``.

So a state's answer is always the sphere checker's own. ``exact_near`` (L∞, rad; default
:data:`EXACT_NEAR`) restricts the exact decisions to states near the start or goal: farther away an
ambiguous state counts as colliding (the pure, conservative sphere model, as everywhere when
``confirm=False``), which keeps the search off near contacts that certification with a safety
margin rejects, and saves the exact model's queries, but makes narrow passages harder. Before
balanced trees and dynamic domains, on 28 MotionBenchMaker problems (3 s budget, a loaded machine)
unset solved 23, 0.3 rad 21 and 0.1 rad 20. With them, on 696 MotionBenchMaker problems (1 s, 1 cm
margin) 1 rad solved as many as unset (692), p95 63–82 ms instead of 77–130 ms on four quarters of
the set; 0 (spheres only) lost 18 of 174 goals close to obstacles.

Balanced trees and dynamic domains (VAMP's ``RRTCSettings`` defaults: radius 4 rad, alpha 1e-4,
smallest 1 rad) are on by default: on the 4 MotionBenchMaker problems that timed out at 1 s
(bookshelf_small/0013, /0093, bookshelf_thin/0089, table_under_pick/0013) all are solved in
0.06–0.2 s with both, 3 with balancing alone, none with neither.

The path goes into the ProblemDefinition like any OMPL planner's, so ``SimpleSetup`` and the
facade's exact verification apply unchanged. Samples come from a generator seeded by ``seed`` or,
unset, by a draw from OMPL's seeded RNG: same seed, same path.

**Other checkers** (the exact pinocchio/coal checker, the tests' toy checkers, a sphere checker
without numba, no edge checker): the kernel cannot call them, so the planner falls back to OMPL's
``RRTConnect`` with the same ``range`` on the SpaceInformation's validators (``compiled`` tells
which ran). Falling back rather than rejecting keeps the id usable from every entry point
(``maru-plan``, the node) whatever the collision model.
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
from maru_planner.planning.planners.planner_params import (
    MAX_JOINT_DISTANCE,
    SAMPLER_SEED,
    PlannerParams,
    stored_params,
)
from maru_planner.planning.planners.registry import ArmPlannerSpec, register
from maru_planner.planning.space import EdgeChecker

# rad. OMPL's automatic range is 2.6 rad for the Panda: on MotionBenchMaker (1 s budget, 0.01 m margin) it timed
# out on 72 of 92 cage and shelf problems that 1 rad solves, and the median of the others fell 80 -> 50 ms.
DEFAULT_RANGE = 1.0
EXACT_NEAR = 1.0  # rad, L-inf: ambiguous states farther from the start and goal count as colliding (module doc)
COMPILED_RRTC_PARAMS: dict[str, ParamSpec] = {
    spec.name: spec
    for spec in (
        ParamSpec(
            "range",
            DEFAULT_RANGE,
            "max extension (rad, L2); 0 = OMPL's automatic 20 % of the space extent",
            lower=0.0,
            upper=MAX_JOINT_DISTANCE,
        ),
        ParamSpec(
            "exact_near",
            EXACT_NEAR,
            "L-inf distance (rad) from the start or goal within which states the spheres leave ambiguous are "
            "decided on the exact model, farther away they count as colliding; unset: everywhere (module doc)",
            lower=0.0,
            upper=MAX_JOINT_DISTANCE,
            optional=True,
        ),
        ParamSpec(
            "balance",
            True,
            "extend the smaller tree while the other has at least twice its nodes (VAMP's "
            "balance); false: alternate, as OMPL's RRTConnect",
        ),  # fmt: skip
        ParamSpec(
            "domain_radius",
            4.0,
            "dynamic domain (rad, L2) a node gets at its first failed extension; "
            "samples farther than its domain from their nearest node are drawn again; 0 = no domains",
            lower=0.0,
            upper=MAX_JOINT_DISTANCE,
        ),
        ParamSpec(
            "domain_alpha",
            1e-4,
            "a domain shrinks by this fraction at each failed extension, grows at each success",
            lower=0.0,
            upper=1.0,
        ),  # fmt: skip
        ParamSpec("domain_min_radius", 1.0, "smallest dynamic domain (rad)", lower=0.0, upper=MAX_JOINT_DISTANCE),
        SAMPLER_SEED,
    )
}

_CAPACITY = 1024  # initial nodes per tree; doubled when full
FIRST_EDGES = 32  # edges of the first kernel call; later calls are sized to last about CALL_SECONDS
_MAX_EDGES = 4096
CALL_SECONDS = 0.002  # between two evaluations of the termination condition


class CompiledRRTConnect(ob.Planner):
    """RRT-Connect in a numba kernel on a sphere checker (see module doc); ``params()``: ``COMPILED_RRTC_PARAMS``."""

    def __init__(self, si: ob.SpaceInformation, edge_checker: EdgeChecker | None = None,
                 name: str = "CompiledRRTConnect"):  # fmt: skip
        super().__init__(si, name)
        self._si = si
        self._edges = edge_checker
        self._params, self._values = stored_params(name, COMPILED_RRTC_PARAMS)
        self._seed_rng = ou.RNG()
        self._fallback: og.RRTConnect | None = None
        self._trees: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._data_states: list = []

    @classmethod
    def create(cls, si: ob.SpaceInformation, params: dict[str, Any], edge_checker: EdgeChecker | None):
        """The registry's factory: a planner on ``si`` with ``params`` (already checked) set."""
        planner = cls(si, edge_checker)
        planner.params().set_params(params)
        return planner

    def params(self) -> PlannerParams:
        """The declared parameters, as OMPL's ``Planner::params()`` (see :mod:`.planner_params`)."""
        return self._params

    @property
    def compiled(self) -> bool:
        """Whether solve() runs the compiled kernel (a sphere checker) rather than the OMPL fallback."""
        return self._edges is not None and is_compiled_sphere_checker(self._edges.checker)

    # --- hooks the MotionPlanner facade reads (maru_planner.planning.planners.registry) ----------------
    def graph_size(self) -> tuple[int, int]:
        """(nodes, edges) of both trees (each tree has one node more than edges)."""
        if self._fallback is not None:
            data = ob.PlannerData(self._si)
            self._fallback.getPlannerData(data)
            return int(data.numVertices()), int(data.numEdges())
        n = self._node_count()
        return n, max(0, n - 2)

    # --- OMPL planner interface ------------------------------------------------------------
    def clear(self) -> None:
        self._trees = None
        self._fallback = None
        self._data_states = []

    def solve(self, ptc: ob.PlannerTerminationCondition) -> ob.PlannerStatus:
        edges = self._edges
        if edges is None or not self.compiled:
            return self._solve_fallback(ptc)
        space = self._si.getStateSpace()
        dim = space.getDimension()
        inputs = self.getPlannerInputStates()
        start_state, goal_state = inputs.nextStart(), inputs.nextGoal()
        if start_state is None or goal_state is None:
            missing = ob.PlannerStatus.INVALID_START if start_state is None else ob.PlannerStatus.INVALID_GOAL
            return ob.PlannerStatus(missing)
        start = np.array([start_state[i] for i in range(dim)])
        goal = np.array([goal_state[i] for i in range(dim)])
        path = self._search(start, goal, edges, ptc)
        if path is None:
            return ob.PlannerStatus(ob.PlannerStatus.TIMEOUT)
        solution = og.PathGeometric(self._si)
        for q in path:
            solution.append(self._ompl_state(q))
        self.getProblemDefinition().addSolutionPath(solution, False, 0.0, self.getName())
        return ob.PlannerStatus(ob.PlannerStatus.EXACT_SOLUTION)

    def getPlannerData(self, data: ob.PlannerData) -> None:  # noqa: N802 (OMPL's name)
        """Both trees: the start tagged as start, the goal as goal, parent→child edges."""
        if self._fallback is not None:
            self._fallback.getPlannerData(data)
            return
        if self._trees is None:
            return
        nodes, parent, st = self._trees
        # PlannerData keeps pointers to the states: they must outlive it (owned by the planner).
        self._data_states = []
        for tree in (0, 1):
            count = int(st[_kernel().N0 + tree])
            states = [self._ompl_state(nodes[tree, i]) for i in range(count)]
            self._data_states += states
            add_root = data.addStartVertex if tree == 0 else data.addGoalVertex
            ids = [add_root(ob.PlannerDataVertex(states[0]))]
            ids += [data.addVertex(ob.PlannerDataVertex(s)) for s in states[1:]]
            for i in range(1, count):
                data.addEdge(ids[parent[tree, i]], ids[i])

    # --- the search ------------------------------------------------------------------------
    def _search(
        self, start: np.ndarray, goal: np.ndarray, edges: EdgeChecker, ptc: ob.PlannerTerminationCondition
    ) -> np.ndarray | None:
        kernel = _kernel()
        checker, gs = edges.checker, edges.gs
        nodes, parent, radius, st = kernel.new_state(start, goal, _CAPACITY)
        self._trees = (nodes, parent, st)
        amb_states = np.empty((int(np.ceil((gs.upper - gs.lower).max() / edges.resolution)) + 2, len(start)))
        fixed = (st, np.empty(len(start)), amb_states, self._tuning(kernel), *self._search_args(kernel, edges),
                 *checker.kernel_inputs(), checker.confirm, self._exact_near())  # fmt: skip
        verdict, batch = False, FIRST_EDGES
        while True:
            t_call = time.perf_counter()
            code = kernel.run(nodes, parent, radius, verdict, batch, *fixed)
            checker.check_count += int(st[kernel.CHECKS])
            st[kernel.CHECKS] = 0
            if code == kernel.SOLVED:
                return kernel.solution_path(nodes, parent, st)
            if code == kernel.NEED_EXACT:
                verdict = checker.first_invalid(gs.full(amb_states[: st[kernel.N_AMB]])) < 0
            elif code == kernel.FULL:
                nodes, parent, radius = kernel.grow(nodes, parent, radius)
                self._trees = (nodes, parent, st)
            batch = next_batch(batch, time.perf_counter() - t_call)
            if ptc():
                return None

    def _search_args(self, kernel, edges: EdgeChecker) -> tuple:
        """The kernel's sampling bounds, generator, range, resolution, base configuration and group indices."""
        gs, seed = edges.gs, self._values["seed"]
        rng = kernel.seed_rng(int(seed if seed is not None else self._seed_rng.uniformInt(0, 2**31 - 2)))
        max_range = float(self._values["range"]) or 0.2 * self._si.getMaximumExtent()
        return gs.lower, gs.upper, rng, max_range, edges.resolution, gs.base, gs.indices.astype(np.int64)

    def _tuning(self, kernel) -> np.ndarray:
        values = self._values
        return kernel.tuning(bool(values["balance"]), float(values["domain_radius"]), float(values["domain_alpha"]),
                             float(values["domain_min_radius"]))  # fmt: skip

    def _exact_near(self) -> float:
        exact_near = self._values["exact_near"]
        return np.inf if exact_near is None else float(exact_near)

    def _node_count(self) -> int:
        if self._trees is None:
            return 0
        st = self._trees[2]
        return int(st[_kernel().N0] + st[_kernel().N1])

    def _solve_fallback(self, ptc: ob.PlannerTerminationCondition) -> ob.PlannerStatus:
        self._fallback = og.RRTConnect(self._si)
        if self._values["range"] > 0:
            self._fallback.setRange(float(self._values["range"]))
        self._fallback.setProblemDefinition(self.getProblemDefinition())
        self._fallback.setup()
        return self._fallback.solve(ptc)

    def _ompl_state(self, q: np.ndarray) -> Any:
        state = self._si.allocState()
        for i, v in enumerate(q):
            state[i] = float(v)
        return state


def next_batch(batch: int, seconds: float) -> int:
    """Edges for the next kernel call after one of ``batch`` edges took ``seconds``, so that it lasts about
    :data:`CALL_SECONDS` (at most doubling)."""
    target = batch * CALL_SECONDS / max(seconds, 1e-6)
    return int(min(max(target, 1), 2 * batch, _MAX_EDGES))


def _kernel():
    """The kernel module: imported on first use (numba loads with it; exact-only callers never need it)."""
    # lazy: numba is only needed once a sphere checker exists, and then it is already loaded
    from maru_planner.planning.planners.kernels import rrtc as rrtc_kernel

    return rrtc_kernel


register(
    ArmPlannerSpec(
        "CompiledRRTConnect",
        "RRT-Connect compiled with numba on the sphere model (VAMP-style); OMPL RRTConnect on other checkers",
        CompiledRRTConnect.create,
        COMPILED_RRTC_PARAMS,
        frozenset({"tree"}),
    )
)
