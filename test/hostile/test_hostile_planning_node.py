"""planning_node against hostile requests and topics (issue 18), through real rclpy clients.

Property-based (hypothesis, fixed seed, bounded examples): every PlanMotion, ComputeIK and
ApplyScene request and every /joint_states and /planning_scene_obstacles message drawn from
``hostile_inputs`` gets an answer within its budget + 0.5 s with a proper code and a one-line
message, never INTERNAL_ERROR, a traceback or a dead node; after each batch a known-good request
still succeeds. RSS grows by at most 50 MB over 10,000 junk /joint_states messages.
The 64-client burst is test_planning_node's.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from hostile_inputs import (
    EASY_GOAL,
    PAPER_START,
    PLANNING_LIMITS,
    SUITE_EXAMPLES,
    PlanningNodeTarget,
    apply_scene_requests,
    params_file_arguments,
    rss_mb,
    run_batch,
    scene_obstacles,
    serve_module,
    tally,
)

from maru_planner_interfaces.msg import PlanningError

pytestmark = pytest.mark.ros

TARGET = "planning_node"
EXAMPLES = {name: SUITE_EXAMPLES[name] for name in ("plan_motion", "compute_ik", "apply_scene", "scene_topic",
                                                   "joint_states")}  # fmt: skip
JUNK_MESSAGES = 10_000
RSS_GROWTH_MB = 50.0
MEASURED: list[str] = []  # lines printed with the counts


@pytest.fixture(scope="module")
def node(node_process, rclpy_session, request):
    from conftest import SpinningNode

    from maru_planner.robot import RobotModel

    process = node_process("maru_planner.ros.planning_node", params_file_arguments("planner.yaml", PLANNING_LIMITS))
    target = PlanningNodeTarget(SpinningNode("hostile_planning_client"), process, RobotModel.maru1())
    yield from serve_module(target, request, MEASURED)


def _still_serving(node) -> None:
    assert node.process.alive(), node.process.log()[-3000:]
    response = node.good_plan()
    assert response.error.code == 1, f"known-good plan failed: {response.error.message}"


def test_hostile_plan_requests(node):
    run_batch(TARGET, node.plan_requests(), node.send_plan, EXAMPLES["plan_motion"])
    _still_serving(node)


def test_hostile_ik_requests(node):
    run_batch(TARGET, node.ik_requests(), node.send_ik, EXAMPLES["compute_ik"])
    _still_serving(node)


@pytest.mark.parametrize("timeout", [math.nan, math.inf, 1e9])
def test_an_ik_timeout_that_is_no_budget_is_refused_at_once(node, timeout):
    response = node.client.compute_ik({"r_hand": np.eye(4)}, group="right_arm", ik_timeout=timeout)
    assert response.error.code == PlanningError.INVALID_REQUEST and "timeout" in response.error.message


def test_hostile_scene_requests(node):
    try:
        run_batch(TARGET, apply_scene_requests(), node.send_scene, EXAMPLES["apply_scene"])
    finally:
        node.restore_scene()
    _still_serving(node)


def test_hostile_scene_topic(node):
    names = ["fuzz_a", "fuzz_b", "desk", "box"]
    try:
        run_batch(TARGET, scene_obstacles(names), lambda m: node.publish(node.scene_topic, m), EXAMPLES["scene_topic"])
    finally:
        node.restore_scene()
    _still_serving(node)


def test_hostile_joint_states_are_never_stored(node):
    run_batch(TARGET, node.joint_state_messages(), lambda m: node.publish(node.joint_states, m),
              EXAMPLES["joint_states"])  # fmt: skip
    assert node.good_state_is_used(), "a plan with an empty start never started at the published state"


def test_rss_over_10000_junk_joint_states(node):
    assert node.good_state_is_used()
    before = rss_mb(node.process.proc.pid)
    node.junk_joint_states(JUNK_MESSAGES)
    assert node.good_state_is_used(), "the node no longer takes /joint_states after the junk"
    after = rss_mb(node.process.proc.pid)
    MEASURED.append(f"planning_node RSS {before:.1f} MB -> {after:.1f} MB over {JUNK_MESSAGES} junk /joint_states")
    assert after - before <= RSS_GROWTH_MB


# ---------------------------------------------------------------- issue 36's validation gaps, through the node
# (the core and CLI cases are test_hostile_limits.py's)


def test_a_cartesian_step_implying_too_many_poses_is_refused_at_once(node):
    hand = node.client.compute_fk(PAPER_START, ["r_hand"])
    assert hand.error.code == PlanningError.SUCCESS, hand.error.message
    pose = hand.poses[0].pose
    pose.position.x += 0.65
    started = time.monotonic()
    response = node.client.cartesian_path([pose], start=PAPER_START, group="right_arm", max_step=1e-9)
    assert response.error.code == PlanningError.INVALID_REQUEST and "max_step" in response.error.message
    assert time.monotonic() - started < 2.0


def test_attempts_out_of_range_are_refused_by_the_service_and_the_action(node):
    response = node.client.plan(EASY_GOAL, start=PAPER_START, attempts=-5, time_budget=1.0)
    assert response.error.code == PlanningError.INVALID_REQUEST and "num_attempts" in response.error.message
    _, result = node.client.plan_action(EASY_GOAL, start=PAPER_START, attempts=-5, time_budget=1.0).result(30.0)
    assert result.error.code == PlanningError.INVALID_REQUEST and "num_attempts" in result.error.message


def test_a_zero_scaling_is_full_speed_for_the_service_and_the_action(node):
    fields = {"start": PAPER_START, "planner_id": "RRTConnect", "seed": 7, "time_budget": 2.0, "velocity_scaling": 0.0}
    service = node.client.plan(EASY_GOAL, **fields)
    _, action = node.client.plan_action(EASY_GOAL, **fields).result(30.0)
    full = node.client.plan(EASY_GOAL, **{**fields, "velocity_scaling": 1.0})
    assert service.error.code == action.error.code == full.error.code == PlanningError.SUCCESS
    durations = [a.trajectory.points[-1].time_from_start for a in (service, action, full)]
    assert durations[0] == durations[1] == durations[2]


@pytest.mark.parametrize("value", [1e300, -1e300])
def test_joint_values_outside_limits_are_refused_by_fk_and_validity(node, value):
    state = {**PAPER_START, "r_arm_j2": value}
    for response in (node.client.check_state_validity(state), node.client.compute_fk(state, ["r_hand"])):
        assert response.error.code == PlanningError.INVALID_ROBOT_STATE and "r_arm_j2" in response.error.message


def test_a_box_of_1e300_is_refused(node):
    try:
        response = node.client.add_obstacle("huge_box", "box", [1e300, 1.0, 1.0], np.eye(4))
        assert response.error.code == PlanningError.INVALID_SCENE and "huge_box" in response.error.message
        assert "huge_box" not in response.obstacle_names
    finally:
        node.restore_scene()


def test_a_planner_parameter_out_of_range_is_refused(node):
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    remote = AsyncParameterClient(node.spinning.node, "planning_node")
    assert remote.wait_for_services(timeout_sec=30.0)

    def answer(future):
        assert node.spinning.wait_for(future.done, timeout=30.0), "no answer from the parameter service"
        return future.result()

    name = "planners.RCRRT.candidates"
    described = answer(remote.describe_parameters([name])).descriptors[0]
    assert described.integer_range[0].to_value == 1000
    result = answer(remote.set_parameters([Parameter(name, value=10**12)])).results[0]
    assert not result.successful


def test_no_broken_invariant_and_enough_inputs(node):
    record = tally(TARGET)
    assert record.broken == 0, record.failures
    assert record.inputs >= sum(EXAMPLES.values()) * 0.9


def _relative(**fields) -> object:
    """A PathConstraints message with a relative pose r_hand -> l_hand (identity unless ``fields`` say)."""
    from maru_planner_interfaces.msg import PathConstraints

    msg = PathConstraints(relative_link_a="r_hand", relative_link_b="l_hand")
    msg.relative_pose.orientation.w = 1.0
    for name, value in fields.items():
        setattr(msg, name, value)
    return msg


def _nan_position() -> object:
    msg = _relative()
    msg.relative_pose.position.x = math.nan
    return msg


@pytest.mark.parametrize(
    ("constraints", "code", "words"),
    [
        (lambda: _relative(relative_link_a="no_such_link"), PlanningError.INVALID_LINK_NAME, "no_such_link"),
        (lambda: _relative(relative_link_b=""), PlanningError.INVALID_REQUEST, "relative_link_b"),
        (_nan_position, PlanningError.INVALID_REQUEST, "NaN"),
        (lambda: _relative(relative_position_tolerance=-0.001), PlanningError.INVALID_REQUEST, "position_tolerance"),
        (lambda: _relative(relative_orientation_tolerance=math.inf), PlanningError.INVALID_REQUEST, "orientation"),
        # the hands are 0.3 m or so apart at the start, not at one pose: the start breaks the constraint
        (_relative, PlanningError.START_STATE_VIOLATES_PATH_CONSTRAINTS, "start"),
    ],
    ids=["unknown-link", "one-link", "nan-pose", "negative-tolerance", "infinite-tolerance", "start-violates"],
)
def test_bad_relative_pose_constraints_get_a_code_and_one_line(node, constraints, code, words):
    from maru_planner.ros.planning_client import plan_request

    request = plan_request(EASY_GOAL, start=PAPER_START, time_budget=1.0)
    request.path_constraints = constraints()
    response = node.client.call(node.client.plan_client, request, 30.0)
    assert response.error.code == code, response.error.message
    assert words in response.error.message and "\n" not in response.error.message
    _still_serving(node)


def test_a_relative_pose_held_at_the_start_is_the_core_one(node):
    """The all-zero quaternion form, converted with the robot and the start (as motion_request does): the links'
    relative pose at the start, the tolerances 0 -> the core's defaults; without a robot it is one clear error."""
    from maru_planner import errors
    from maru_planner.planning.constraints import RelativePoseConstraint
    from maru_planner.planning.requests import start_configuration
    from maru_planner.ros.manipulation import path_constraints
    from maru_planner_interfaces.msg import PathConstraints

    msg = PathConstraints(relative_link_a="r_hand", relative_link_b="l_hand")
    msg.relative_pose.orientation.w = 0.0  # geometry_msgs' default quaternion is the identity (0, 0, 0, 1)
    robot = node.robot
    relative = path_constraints(msg, "base_link", robot, PAPER_START).relative
    expected = RelativePoseConstraint.held(robot, start_configuration(robot, PAPER_START, []), "r_hand", "l_hand")
    assert relative is not None and np.allclose(relative.relative, expected.relative)
    assert (relative.position_tolerance, relative.orientation_tolerance) == (1e-3, 1e-2)
    with pytest.raises(errors.InvalidRequest, match="start state"):
        path_constraints(msg, "base_link")
