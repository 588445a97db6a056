"""Searching with a roadmap planner (the ``roadmap`` capability): the context keeps one roadmap between queries.

A roadmap built before the last scene change is "stale": its answer is checked against the current scene in one
batched call (cheap) and returned if free. Only when that check fails is the whole roadmap re-validated, and
rebuilt if any milestone or edge died. The seed seeds OMPL while a roadmap is created and grown, so a fresh
planner builds the same roadmap for the same seed.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from maru_planner.planning.context import PlanningContext
from maru_planner.planning.planners.ompl_search import seeded_ompl
from maru_planner.planning.planners.registry import ArmPlannerSpec, get_spec
from maru_planner.planning.planners.roadmap import Roadmap
from maru_planner.planning.problem import PlanningProblem


def search_roadmap(problem: PlanningProblem, params: dict[str, Any], seed: int, deadline: float,
                   stats: Any) -> tuple[np.ndarray | None, str | None]:  # fmt: skip
    """Query the context's roadmap (module doc); (path | None, None)."""
    context, spec = problem.context, get_spec(problem.planner_id)
    with seeded_ompl(seed):
        roadmap = _roadmap_for(problem, spec, params)
        stale = roadmap.scene_epoch != context.scene_key()
        path = _query(problem, roadmap, deadline, stats)
        if path is None or not stale:
            return path, None
        t_check = time.monotonic()
        path_ok = roadmap.edges.path_valid(path)
        stats.validation_time += time.monotonic() - t_check
        if path_ok:
            return path, None
        report = roadmap.revalidate()
        context.last_revalidation = report
        stats.validation_time += report.seconds
        if report.still_valid:  # cannot happen with a deterministic checker; keep the roadmap if it does
            roadmap.scene_epoch = context.scene_key()
            return path, None
        context.roadmaps.clear()
        roadmap = _roadmap_for(problem, spec, params)
        return _query(problem, roadmap, deadline, stats), None


def _roadmap_for(problem: PlanningProblem, spec: ArmPlannerSpec, params: dict[str, Any]) -> Roadmap:
    context: PlanningContext = problem.context
    gs = problem.setup.gs
    outside = np.setdiff1d(np.arange(len(gs.base)), gs.indices)
    key = (spec.id, tuple(gs.indices), tuple(np.round(gs.base[outside], 9)), problem.resolution,
           tuple(params.items()), id(problem.checker))  # fmt: skip
    roadmap = context.roadmaps.get(key)
    if roadmap is None:
        roadmap = Roadmap(gs, problem.checker, problem.resolution, spec.id, params)
        roadmap.scene_epoch = context.scene_key()
        context.roadmaps = {key: roadmap}  # one roadmap at a time: bounded memory
    return roadmap


def _query(problem: PlanningProblem, roadmap: Roadmap, deadline: float, stats: Any) -> np.ndarray | None:
    stats.roadmap_reused = roadmap.queries > 0
    nodes = problem.config.prm_roadmap_nodes
    if roadmap.milestones < nodes:
        before = roadmap.build_time
        roadmap.build(nodes, deadline)
        stats.roadmap_build_time += roadmap.build_time - before
    problem.monitor.report("search", nodes=roadmap.milestones)
    seconds = deadline - time.monotonic()
    if seconds <= 0:
        return None
    _mode, path = roadmap.query(problem.start, problem.goal, seconds)
    stats.nodes, stats.edges = roadmap.milestones, roadmap.edge_count
    return path
