"""A plan as a straight line of stages: the request adapters build the problem, the path stages run in order,
then the check stages (``planning/stages``). No stage calls back into the facade: a verify re-plan runs the path
stages again through :attr:`PlanningProblem.replan`, a repair a pipeline of its own."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from maru_planner.monitor import PlanMonitor
from maru_planner.planning.adapters import build_problem
from maru_planner.planning.checkers import collision_model_of
from maru_planner.planning.context import PlanningContext
from maru_planner.planning.problem import PlanningProblem
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStats, PlanStatus, set_failure

PathStage = Callable[[PlanningProblem, MotionResult], None]  # raises a typed error to fail the request
CheckStage = Callable[[PlanningProblem, MotionResult], MotionResult]  # returns the result, maybe failed or new


class Pipeline:
    """``path_stages`` then ``check_stages``, each called once, in order (a check may re-plan the path stages)."""

    def __init__(self, path_stages: Sequence[PathStage], check_stages: Sequence[CheckStage] = ()):
        self.path_stages, self.check_stages = tuple(path_stages), tuple(check_stages)

    def run(self, context: PlanningContext, request: MotionRequest, monitor: PlanMonitor, t0: float) -> MotionResult:
        """Plan ``request``; never raises (errors become the result's status and message)."""
        problem, result = self.plan_path(context, request, monitor, t0, context.config.resolution)
        if problem is not None:
            for check in self.check_stages:
                result = check(problem, result)
        result.stats.total_time = time.monotonic() - t0
        return result

    def plan_path(self, context: PlanningContext, request: MotionRequest, monitor: PlanMonitor, t0: float,
                  resolution: float) -> tuple[PlanningProblem | None, MotionResult]:  # fmt: skip
        """The problem (None if the request is refused) and the result of the path stages at ``resolution``."""
        stats = PlanStats(
            planner_id=getattr(request, "planner_id", "") or context.config.default_planner,
            collision_model=collision_model_of(context.checker),
        )
        result = MotionResult(status=PlanStatus.PLANNING_FAILED, stats=stats)
        problem = None
        try:
            problem = build_problem(context, request, result, monitor, t0, resolution)
            problem.replan = lambda finer: self.plan_path(context, request, monitor, t0, finer)[1]
            for stage in self.path_stages:
                stage(problem, result)
        except Exception as exc:  # a typed error, or a bug or checker failure: reported, the planner keeps serving
            set_failure(result, exc)
            result.path, result.trajectory = None, None
        return problem, result
