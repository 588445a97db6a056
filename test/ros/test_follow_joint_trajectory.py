"""The ros2_control path (issue 39): planning_node with execution_action_type control_msgs/action/FollowJointTrajectory
sends its certified trajectory to arm_sim_node's follow_joint_trajectory server (control_msgs built from
interfaces/control_msgs when no real one is installed). Plan + execute succeeds and the arm ends at the goal
(/joint_states); a trajectory for joints the arm lacks (a Panda arm under /panda given Maru-1's plan) comes back as
control_msgs' INVALID_JOINTS in the plan goal's execution_error_code; SIGTERM stops the arm with no traceback.
Without a node: multi-DOF goals refused as INVALID_JOINTS, control_msgs' feedback and result built.
"""

from __future__ import annotations

import sys
import threading

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from conftest import connected_planning_client, wait_until_node_has_joint_states
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointComponentTolerance
from sensor_msgs.msg import JointState

from maru_planner.errors import InvalidJointNames
from maru_planner.execution.tolerances import ResultCode
from maru_planner.paths import config_path
from maru_planner.robot import RobotModel
from maru_planner.ros.follow_joint_trajectory import FollowJointTrajectoryShape, follow_joint_trajectory_type
from maru_planner.ros.planning_client import status_name
from maru_planner.ros.planning_parameters import FOLLOW_JOINT_TRAJECTORY
from maru_planner_interfaces.msg import PlanningError

pytestmark = pytest.mark.ros
FJT = FollowJointTrajectory.Result
SUCCEEDED, ABORTED = 4, 6  # action_msgs/GoalStatus
SCENE = str(config_path("scenes/maru13_desk_box.yaml"))
PANDA_ARGS = ["--ros-args", "-r", "__ns:=/panda", "-p", "robot:=panda", "-p", "initial_state:=default", "-p",
              "joint_state_rate:=50.0"]  # fmt: skip
ARM_ARGS = ["--ros-args", "--params-file", str(config_path("arm_sim.yaml")), "-p", f"scene_file:={SCENE}"]


class LatestState:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.msg: JointState | None = None

    def __call__(self, msg: JointState) -> None:
        with self.lock:
            self.msg = msg

    def positions(self) -> dict[str, float]:
        with self.lock:
            assert self.msg is not None
            return dict(zip(self.msg.name, self.msg.position))


@pytest.fixture(scope="module")
def ros2_control_path(node_process, tester):
    arm = node_process("maru_planner.ros.arm_sim_node", ARM_ARGS)
    panda = node_process("maru_planner.ros.arm_sim_node", PANDA_ARGS)
    planner = node_process(
        "maru_planner.ros.planning_node",
        ["--ros-args", "--params-file", str(config_path("planner.yaml")), "-p",
         f"execution_action_type:={FOLLOW_JOINT_TRAJECTORY}", "-p", "execution_action:=follow_joint_trajectory"],
    )  # fmt: skip
    state = LatestState()
    tester.node.create_subscription(JointState, "joint_states", state, 10)
    client = connected_planning_client(tester, planner)
    assert tester.wait_for(lambda: state.msg is not None, timeout=60.0), arm.log()
    wait_until_node_has_joint_states(client)  # the plans start from the arm's /joint_states
    yield client, state, arm, panda
    assert panda.alive() and planner.alive(), panda.log() + planner.log()


def _describe(status: int, result) -> str:
    return (
        f"{status_name(status)}: plan {result.error.code} {result.error.message}; "
        f"execution {result.execution_error_code} {result.execution_error_string}"
    )


def _home() -> dict[str, float]:
    robot = RobotModel.maru1()
    return dict(zip(robot.joint_names, robot.named_state("home").tolist()))


def test_the_executor_codes_are_control_msgs():
    assert {code.name: int(code) for code in ResultCode} == {
        name: getattr(FJT, name) for name in dir(FJT) if name.isupper() and isinstance(getattr(FJT, name), int)
    }


def test_plan_and_execute_through_follow_joint_trajectory(ros2_control_path):
    planning, state, arm, _ = ros2_control_path
    goal = _home()
    goal["waist_yaw"] += 0.25
    goal["l_arm_j4"] += 0.4
    handle = planning.plan_action(goal, execute=True, seed=1, time_budget=10.0)
    status, result = handle.result(timeout=90.0)
    assert status == SUCCEEDED and result.execution_error_code == FJT.SUCCESSFUL, _describe(status, result)
    assert result.error.code == PlanningError.SUCCESS and result.stats.certified
    assert 0.0 <= result.execution_tracking_error <= 0.05  # from control_msgs' feedback error
    duration = result.trajectory.points[-1].time_from_start
    assert result.execution_time >= duration.sec + 1e-9 * duration.nanosec
    here = state.positions()
    assert np.allclose([here[n] for n in goal], list(goal.values()), atol=0.011), arm.log()


def test_joints_the_arm_lacks_are_invalid_joints(ros2_control_path):
    planning, _, _, panda = ros2_control_path
    assert not planning.set_parameters(execution_action="/panda/follow_joint_trajectory")
    try:
        goal = _home()
        goal["waist_yaw"] += 0.1
        status, result = planning.plan_action(goal, execute=True, seed=2, time_budget=10.0).result(timeout=90.0)
    finally:
        assert not planning.set_parameters(execution_action="follow_joint_trajectory")
    assert status == ABORTED and result.error.code == PlanningError.SUCCESS, _describe(status, result)
    assert result.execution_error_code == FJT.INVALID_JOINTS, _describe(status, result) + panda.log()
    assert "not in the simulated arm" in result.execution_error_string and "\n" not in result.execution_error_string


def test_sigterm_stops_the_arm_without_a_traceback(ros2_control_path):
    _, _, arm, _ = ros2_control_path
    assert arm.alive(), arm.log()
    arm.stop()  # SIGTERM while publishing joint_states at 250 Hz
    assert arm.proc.returncode == 0 and "Traceback" not in arm.log(), arm.log()


def test_multi_dof_goals_are_invalid_joints_and_feedback_is_control_msgs():
    shape = FollowJointTrajectoryShape(FollowJointTrajectory)
    shape.check(FollowJointTrajectory.Goal())  # revolute joints only: fine
    goal = FollowJointTrajectory.Goal()
    goal.multi_dof_trajectory.joint_names = ["base_planar"]
    with pytest.raises(InvalidJointNames, match="base_planar"):
        shape.check(goal)
    goal = FollowJointTrajectory.Goal(component_goal_tolerance=[JointComponentTolerance(joint_name="floating")])
    with pytest.raises(InvalidJointNames, match="floating"):
        shape.check(goal)
    feedback = shape.feedback(Time(sec=3), ["a", "b"], np.array([1.0, 2.0]), np.array([0.5, 2.0]))
    assert isinstance(feedback, FollowJointTrajectory.Feedback) and feedback.header.stamp.sec == 3
    assert list(feedback.error.positions) == [0.5, 0.0] and list(feedback.joint_names) == ["a", "b"]
    refused = shape.refused(FJT.INVALID_JOINTS, "two\nlines")
    assert refused.error_code == FJT.INVALID_JOINTS and "\n" not in refused.error_string


def test_without_control_msgs_there_is_no_follow_joint_trajectory_type(monkeypatch):
    assert follow_joint_trajectory_type() is FollowJointTrajectory
    monkeypatch.setitem(sys.modules, "control_msgs.action", None)  # import fails as if not installed
    assert follow_joint_trajectory_type() is None
