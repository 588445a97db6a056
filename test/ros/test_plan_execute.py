"""Plan, then execute through both nodes (issue 39, step 3): planning_node's plan_motion action with ``execute`` sends
its certified trajectory to arm_sim_node's execute_trajectory; the start of every plan is the arm's /joint_states.
One arm_sim_node and one planning_node (config/planner.yaml: the desk and box scene, also given to the arm) for the
module: plan -> execute -> plan again, a cancel during execution, an execution the arm refuses (a start far from the
arm), and an unreachable execution action (set at run time) -- each a code and one line, the node serving on.
"""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
from conftest import connected_planning_client, wait_until_node_has_joint_states

from maru_planner.paths import config_path
from maru_planner.robot import RobotModel
from maru_planner.ros.planning_client import status_name
from maru_planner_interfaces.action import ExecuteTrajectory
from maru_planner_interfaces.action import PlanMotion as PlanMotionAction
from maru_planner_interfaces.msg import PlanningError

pytestmark = pytest.mark.ros
R = PlanMotionAction.Result
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6  # action_msgs/GoalStatus
SCENE = str(config_path("scenes/maru13_desk_box.yaml"))


@pytest.fixture(scope="module")
def home() -> dict[str, float]:
    robot = RobotModel.maru1()
    return dict(zip(robot.joint_names, robot.named_state("home").tolist()))


@pytest.fixture(scope="module")
def planning(node_process, tester):
    arm = node_process(
        "maru_planner.ros.arm_sim_node",
        ["--ros-args", "--params-file", str(config_path("arm_sim.yaml")), "-p", f"scene_file:={SCENE}"],
    )
    node = node_process(
        "maru_planner.ros.planning_node", ["--ros-args", "--params-file", str(config_path("planner.yaml"))]
    )
    client = connected_planning_client(tester, node)
    wait_until_node_has_joint_states(client)  # the plans start from the arm's /joint_states
    yield client
    assert arm.alive(), "arm_sim_node died:\n" + arm.log()
    assert node.alive(), "planning_node died:\n" + node.log()


class Stages:
    def __init__(self):
        self.seen: list[str] = []
        self.tracking: list[float] = []
        self.executing = threading.Event()

    def __call__(self, feedback) -> None:
        self.seen.append(feedback.stage)
        if feedback.stage == "executing":
            self.tracking.append(feedback.tracking_error)
            self.executing.set()


def _moved(home: dict[str, float], **offsets: float) -> dict[str, float]:
    return {name: value + offsets.get(name, 0.0) for name, value in home.items()}


def _describe(status: int, result) -> str:
    return (
        f"{status_name(status)}: plan {result.error.code} {result.error.message}; "
        f"execution {result.execution_error_code} {result.execution_error_string}"
    )


def _execute(planning, goal: dict[str, float], **fields):
    stages = Stages()
    goal_handle = planning.plan_action(goal, execute=True, seed=1, time_budget=10.0, feedback_callback=stages, **fields)
    return goal_handle, stages


def test_plan_execute_and_plan_again_from_the_joint_states(planning, home):
    there = _moved(home, waist_yaw=0.3, l_arm_j4=0.5)
    for goal in (there, home):  # no start state given: the node takes the arm's /joint_states
        goal_handle, stages = _execute(planning, goal)
        status, result = goal_handle.result(timeout=60.0)
        assert status == SUCCEEDED and result.execution_error_code == 0, _describe(status, result)
        assert result.error.code == PlanningError.SUCCESS and result.stats.certified
        assert "executing" in stages.seen and any(
            math.isfinite(e) for e in stages.tracking
        )  # NaN until the arm reports
        assert 0.0 <= result.execution_tracking_error <= 0.05
        duration = result.trajectory.points[-1].time_from_start
        assert result.execution_time >= duration.sec + 1e-9 * duration.nanosec
    arrived = planning.compute_fk(links=["base_link"])  # the node's state is the arm's: back home
    assert arrived.error.code == PlanningError.SUCCESS
    plain = planning.plan(there, time_budget=10.0, seed=2)  # the service plans without executing
    assert plain.error.code == PlanningError.SUCCESS and plain.trajectory.points
    assert np.allclose(plain.trajectory.points[0].positions, list(home.values()), atol=0.011)


def test_cancelling_the_plan_goal_cancels_the_execution(planning, home):
    goal_handle, stages = _execute(planning, _moved(home, waist_yaw=0.4, l_arm_j4=0.5))
    assert stages.executing.wait(timeout=60.0), stages.seen
    assert goal_handle.cancel()
    status, result = goal_handle.result(timeout=30.0)
    assert status == CANCELED and result.execution_error_code == R.EXECUTION_CANCELED, _describe(status, result)
    assert result.error.code == PlanningError.SUCCESS  # the plan itself was fine


def test_an_execution_the_arm_refuses_aborts_with_its_code(planning, home):
    """A start state given by the client, 0.2 rad or more from the arm: the arm's start tolerance refuses it."""
    start = _moved(home, waist_yaw=-0.2)
    goal_handle, _ = _execute(planning, _moved(home, waist_yaw=0.2), start=start)
    status, result = goal_handle.result(timeout=60.0)
    assert status == ABORTED and result.error.code == PlanningError.SUCCESS, _describe(status, result)
    assert result.execution_error_code == ExecuteTrajectory.Result.INVALID_GOAL
    assert "\n" not in result.execution_error_string and result.execution_error_string
    again = planning.plan(home, time_budget=10.0, seed=3)  # the node serves on
    assert again.error.code == PlanningError.SUCCESS


def test_an_unreachable_execution_action_is_one_code_and_one_line(planning, home):
    """execution_action changed at run time (PlanningClient.set_parameters) to a name no server has."""
    assert not planning.set_parameters(execution_action="no_such_controller", execution_server_timeout=0.2)
    try:
        goal_handle, _ = _execute(planning, _moved(home, waist_yaw=0.2))
        status, result = goal_handle.result(timeout=60.0)
        assert status == ABORTED and result.error.code == PlanningError.SUCCESS, _describe(status, result)
        assert result.execution_error_code == R.EXECUTION_SERVER_UNAVAILABLE
        assert "no_such_controller" in result.execution_error_string and "\n" not in result.execution_error_string
        assert math.isnan(result.execution_tracking_error)
        rejected = planning.set_parameters(execution_action="not a name")
        assert "execution_action" in rejected["execution_action"] and "\n" not in rejected["execution_action"]
    finally:
        assert not planning.set_parameters(execution_action="execute_trajectory", execution_server_timeout=2.0)
    assert planning.plan(home, time_budget=10.0).error.code == PlanningError.SUCCESS  # the node serves on


def test_an_uncertified_plan_is_not_executed(planning, home):
    assert not planning.set_parameters(certify=False)
    try:
        goal_handle, stages = _execute(planning, _moved(home, waist_yaw=0.1))
        status, result = goal_handle.result(timeout=60.0)
    finally:
        assert not planning.set_parameters(certify=True)
    assert status == ABORTED and result.execution_error_code == R.EXECUTION_NOT_CERTIFIED, _describe(status, result)
    assert result.error.code == PlanningError.SUCCESS and "executing" not in stages.seen
