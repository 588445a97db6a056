"""execution/executor.py on a simulated Maru-1: a time-optimal trajectory is followed within 0.02 rad and on
time; tolerance violations abort with control_msgs' codes; cancel brings the arm to rest within its limits; a
trajectory through an obstacle (timed without any collision check, in this test only) is reported as contacts
with their depth; bad goals are typed errors and move nothing; a new goal preempts the running one."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.errors import InvalidJointNames, InvalidState
from maru_planner.execution.executor import ArmController
from maru_planner.execution.interpolation import TrajectoryPoints, checked_points
from maru_planner.execution.tolerances import ResultCode, StartToleranceViolated, tolerances
from maru_planner.physics.arm_model import build_arm_model
from maru_planner.physics.arm_sim import ArmSim
from maru_planner.planning.problems import PROBLEMS
from maru_planner.scene import Obstacle, Scene
from maru_planner.trajectory import Limits, parameterize


@pytest.fixture(scope="module")
def setup(maru1):
    """Maru-1 at the paper's 13-DOF start, and a toppra trajectory (full velocity scaling) over three waypoints."""
    names = maru1.groups["upper_body"]
    start = np.array(PROBLEMS["maru13"].start, dtype=float)
    mid = start.copy()
    mid[[0, 1]] += [0.3, 0.5]
    goal = mid.copy()
    goal[[4, 7]] += [0.5, -0.4]
    index = maru1.joint_indices(names)
    limits = Limits.scaled(maru1.velocity_limits[index], maru1.acceleration_limits[index])
    trajectory, _ = parameterize(np.stack([start, mid, goal]), names, limits, "toppra",
                                 curve_free=lambda states, deviation: True, max_deviation=0.05)  # fmt: skip
    q0 = maru1.neutral().copy()
    q0[index] = start
    points = checked_points(names, trajectory.times, trajectory.positions, trajectory.velocities,
                            trajectory.accelerations)  # fmt: skip
    return maru1, q0, points


def _controller(robot, q0, scene=None) -> ArmController:
    sim = ArmSim(build_arm_model(robot, scene, q0=q0))
    sim.reset(q0)
    return ArmController(sim)


def test_follows_a_time_optimal_trajectory_within_tolerance_and_on_time(setup):
    robot, q0, points = setup
    result = _controller(robot, q0).run(points)
    assert result.success, result.message
    assert np.max(result.max_error) <= 0.02
    assert result.overrun is not None and result.overrun <= 0.05
    assert result.contacts == [] and result.saturated_steps == 0
    assert len(result.times) > 0.9 * points.duration * 250  # 250 Hz samples
    np.testing.assert_allclose(result.actual[-1], points.positions[-1], atol=0.01)


def test_path_tolerance_violation_aborts_and_the_arm_comes_to_rest(setup):
    robot, q0, points = setup
    controller = _controller(robot, q0)
    result = controller.run(points, tolerances(13, points.duration, path_position=1e-5))
    assert result.code == ResultCode.PATH_TOLERANCE_VIOLATED and not result.success
    assert "path tolerance violated" in result.message and "'" in result.message
    assert result.times[-1] < points.duration and not controller.busy
    controller.settle(1.0)
    assert np.max(np.abs(controller.sim.state().velocities)) < 1e-3


def test_goal_tolerance_violation_aborts_when_the_goal_is_out_of_reach(setup):
    robot, q0, _ = setup
    names = ["r_arm_j1"]
    start = q0[robot.joint_indices(names)]
    beyond = robot.upper_limits[robot.joint_indices(names)] + 0.05  # the joint's stop is in the way
    points = checked_points(names, [0.0, 1.0], [start, beyond])  # positions only: linear
    result = _controller(robot, q0).run(points, tolerances(1, 1.0, path_position=0.0, goal_time=0.3))
    assert result.code == ResultCode.GOAL_TOLERANCE_VIOLATED
    assert "r_arm_j1" in result.message and result.finished_at is None and result.overrun is None


def test_cancel_brings_the_arm_to_rest_within_its_limits(setup):
    robot, q0, points = setup
    controller = _controller(robot, q0)
    result = controller.run(points, cancel_at=0.5 * points.duration)
    assert result.cancelled and not result.success and not controller.busy
    speed = np.abs(controller.sim.state().velocities)
    assert np.max(speed) > 0.1  # cancelled at speed
    ramp_time = controller.stop_duration
    _, _, deceleration = controller.ramp(0.0)
    assert np.all(np.abs(deceleration) <= robot.acceleration_limits + 1e-9)
    assert 0.0 < ramp_time <= np.max(speed / robot.acceleration_limits) + 1e-9
    controller.settle(ramp_time + 0.3)
    state = controller.sim.state()
    assert np.max(np.abs(state.velocities)) < 1e-3
    assert robot.within_limits(state.positions, tol=1e-3)
    np.testing.assert_allclose(state.positions, controller.ramp(ramp_time)[0], atol=2e-3)


def test_a_trajectory_through_an_obstacle_is_reported_as_contact(setup):
    robot, q0, points = setup
    halfway = q0.copy()
    halfway[robot.joint_indices(points.joint_names)] = points.positions[len(points.times) // 2]
    hand = robot.frame_pose(halfway, "r_hand")[:3, 3]
    scene = Scene([Obstacle("block", "box", size=(0.08, 0.08, 0.08), pose=list(hand))])
    result = _controller(robot, q0, scene).run(points)
    assert result.contacts and result.max_penetration > 0.0
    assert {c.obstacle for c in result.contacts} == {"block"}
    assert any(c.link.startswith("r_") for c in result.contacts)


def test_bad_goals_are_typed_errors_and_move_nothing(setup):
    robot, q0, points = setup
    controller = _controller(robot, q0)
    renamed = TrajectoryPoints(["waist_yaw", "elbow"], points.times, points.positions[:, :2])
    with pytest.raises(InvalidJointNames, match="elbow"):
        controller.start(renamed)
    away = TrajectoryPoints(points.joint_names, points.times, points.positions + 0.05)
    with pytest.raises(StartToleranceViolated, match=r"0\.0500 rad .*waist_yaw.*\(start tolerance 0\.01\)"):
        controller.start(away)
    assert isinstance(StartToleranceViolated("x"), InvalidState)
    assert not controller.busy and controller.sim.time == 0.0


def test_a_new_goal_preempts_the_running_one(setup):
    robot, q0, points = setup
    controller = _controller(robot, q0)
    controller.start(points)
    for _ in range(50):
        controller.step()
    here = controller.sim.state().positions[robot.joint_indices(points.joint_names)]
    controller.start(checked_points(points.joint_names, [0.0, 0.5], [here, here]))
    assert controller.preempted is not None and controller.preempted.cancelled
    assert controller.preempted.message == "preempted by a new goal"
    result = None
    while result is None:
        result = controller.step()
    assert result.success
