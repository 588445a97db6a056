"""Solving an OMPL-style planner on the problem's group setup, OMPL's seed held for the whole solve.

Every OMPL search in the process runs under :data:`OMPL_LOCK`, because OMPL's seed generator is process-global:
reseeding it right before the planner is built and solved is what makes "same seed, same path" hold.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import util as ou

from maru_planner.planning.planners.registry import ProvesFailure, ReportsGraphSize, get_spec
from maru_planner.planning.problem import PlanningProblem

OMPL_LOCK = threading.RLock()
ou.setLogLevel(ou.LOG_WARN)  # OMPL's INFO chatter would mix into CLI output


@contextlib.contextmanager
def seeded_ompl(seed: int) -> Iterator[None]:
    """Hold the OMPL lock with OMPL's seed generator restarted from ``seed`` (its warning silenced)."""
    with OMPL_LOCK:
        level = ou.getLogLevel()
        ou.setLogLevel(ou.LOG_NONE)
        try:
            ou.RNG.setSeed(int(seed) % (2**31 - 2) + 1)
        finally:
            ou.setLogLevel(level)
        yield


def search_tree(problem: PlanningProblem, params: dict[str, Any], seed: int, deadline: float,
                stats: Any) -> tuple[np.ndarray | None, str | None]:  # fmt: skip
    """One solve of a fresh planner on the group's reused setup; (path | None, proven-failure message | None)."""
    spec = get_spec(problem.planner_id)
    assert spec.factory is not None
    setup = problem.setup
    gs, edges, ss = setup.gs, setup.edges, setup.ss
    si = ss.getSpaceInformation()
    with seeded_ompl(seed):
        ss.setStartAndGoalStates(gs.to_state(problem.start), gs.to_state(problem.goal))
        planner = spec.factory(si, params, edges)
        ss.setPlanner(planner)
        ptc = ob.timedPlannerTerminationCondition(max(0.0, deadline - time.monotonic()))
        with problem.monitor.attach(ptc):
            ss.solve(ptc)
    stats.nodes, stats.edges = graph_size(planner, si)
    if ss.haveExactSolutionPath():
        return np.array([gs.to_array(s) for s in ss.getSolutionPath().getStates()]), None
    return None, planner.failure_proof() if isinstance(planner, ProvesFailure) else None


def graph_size(planner: Any, si: Any) -> tuple[int, int]:
    """(nodes, edges) the planner built: its own count if it reports one, else from a PlannerData copy."""
    if isinstance(planner, ReportsGraphSize):
        return planner.graph_size()
    data = ob.PlannerData(si)
    planner.getPlannerData(data)
    return int(data.numVertices()), int(data.numEdges())
