"""The certify stage reports its time under certify_time, whichever way the path was proven (issue 41)."""

from __future__ import annotations

import pytest

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig
from maru_planner.planning.problems import PROBLEMS
from maru_planner.robot import RobotModel
from maru_planner.scene import Scene

PROBLEM = PROBLEMS["maru13"]


@pytest.fixture(scope="module")
def planned():
    robot = RobotModel.maru1()
    names = robot.groups[PROBLEM.group]
    request = MotionRequest(PROBLEM.group, start=PROBLEM.start_dict(names), goal_joints=PROBLEM.goal_dict(names),
                            time_budget=30.0, seed=1)  # fmt: skip

    def plan(config: PlannerConfig):
        return MotionPlanner.from_scene(robot, Scene.from_yaml(PROBLEM.scene_path), config).plan(request)

    return plan


def test_a_default_plan_reports_its_certification_time(planned):
    result = planned(PlannerConfig())  # toppra's blends: the whole curve is proven inside time parameterisation
    assert result.success and result.stats.certified and result.curve_certified
    assert result.stats.certify_time == pytest.approx(result.curve_proof.certify_time)
    assert 0.0 < result.stats.certify_time <= result.stats.parameterize_time


def test_a_path_certified_after_timing_reports_its_time(planned):
    result = planned(PlannerConfig(time_parameterization="trapezoid"))  # no blends: the certify stage proves the path
    assert result.success and result.stats.certified and not result.curve_certified
    assert result.stats.certify_time > 0.0
