"""End-to-end tests of planning_node through real rclpy clients (node in its own process).

The node is started ONCE for this module; tests run in file order and the few
that depend on the node's state (no /joint_states yet, scene contents) say so.
"""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import GROUP_JOINTS, PAPER_GOAL, PAPER_START, connected_planning_client, rss_mb

# serial: its bursts, storms and admission timings load the machine on purpose (make test runs it alone)
pytestmark = [pytest.mark.ros, pytest.mark.serial]

NODE = "/planning_node"
# Fixed seeds keep the test quick and repeatable (the core is deterministic per seed); the
# spread over seeds is the planning benchmark's business. Plain RRT: see below.
PAPER_SEEDS = {"RRTConnect": 3, "PRM": 3, "GoalBiasedRRT": 4, "RCRRT": 3}
PAPER_BUDGET = 20.0
FINE_RESOLUTION = 0.005  # rad, finer than the node's 0.02


# ---------------------------------------------------------------- fixtures and helpers


@pytest.fixture(scope="module")
def core():
    """The core objects the tests use to check answers independently of the node."""
    from maru_planner.collision import CollisionChecker
    from maru_planner.paths import config_path, urdf_path
    from maru_planner.robot import RobotModel
    from maru_planner.scene import Scene

    robot = RobotModel.from_urdf(str(urdf_path("maru1_upper_body.urdf")), str(urdf_path("maru1_upper_body.srdf")))
    scene = Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml"))
    return robot, scene, CollisionChecker(robot, scene)


@pytest.fixture(scope="module")
def client(planner_node, tester):
    return connected_planning_client(tester, planner_node)


@pytest.fixture(scope="module")
def joint_states(client, tester):
    """The module's /joint_states publisher, proven delivered (see ``_plan_from_joint_states``).

    Created by the first test that needs it, so the tests before it see a node without joint states.
    """
    from sensor_msgs.msg import JointState

    publisher = tester.node.create_publisher(JointState, "/joint_states", 10)
    assert tester.wait_for(lambda: publisher.get_subscription_count() > 0, timeout=60.0)
    state = _easy_goal(PAPER_START, 0.1)
    response = _plan_from_joint_states(client, tester, publisher, state, _easy_goal(PAPER_START, 0.3))
    _assert_success(response)
    return publisher


def _publish_state(tester, publisher, state: dict[str, float], times: int = 3) -> None:
    from maru_planner.ros.planning_conversions import joint_state_msg

    for _ in range(times):
        publisher.publish(joint_state_msg(list(state), list(state.values()), tester.node.get_clock().now().to_msg()))
        time.sleep(0.02)


def _starts_at(response, state: dict[str, float]) -> bool:
    if response.error.code != _codes().SUCCESS:
        return False
    names, _, positions = _positions(response)
    return bool(np.allclose(positions[0], [state[n] for n in names], atol=1e-6))


def _plan_from_joint_states(client, tester, publisher, state, goal, seed: int = 1, timeout: float = 60.0):
    """Publish ``state`` on /joint_states and plan with an empty start until the plan starts there.

    /joint_states and the plan request travel on different DDS endpoints: nothing orders them, and
    right after discovery the node may not have matched a new publisher yet (what it misses is lost).
    Returns the last response; the caller's assertions say what was wrong if it never started there.
    """
    deadline = time.monotonic() + timeout
    while True:
        _publish_state(tester, publisher, state)
        response = client.plan(goal, start=None, time_budget=5.0, seed=seed)
        if _starts_at(response, state) or time.monotonic() > deadline:
            return response
        time.sleep(0.1)


def _codes():
    from maru_planner_interfaces.msg import PlanningError

    return PlanningError


def _assert_success(response):
    from maru_planner.ros.planning_conversions import code_name

    assert response.error.code == _codes().SUCCESS, f"{code_name(response.error.code)}: {response.error.message}"


def _positions(response) -> tuple[list[str], np.ndarray, np.ndarray]:
    from maru_planner.ros.planning_conversions import trajectory_positions

    return trajectory_positions(response.trajectory)


def _shuffled(values: dict[str, float]) -> dict[str, float]:
    """Same joint values, keys in a different order: the node must match by name."""
    names = list(values)
    order = names[1::2] + names[0::2]
    return {name: values[name] for name in reversed(order)}


def _full_q(robot, values: dict[str, float]) -> np.ndarray:
    from maru_planner.runtime import configuration

    return configuration(robot, values)


def _assert_path_free(core, names, positions, scene=None, fixed=None):
    """Every state on the piecewise-linear path is collision-free at FINE_RESOLUTION.

    Joints outside ``names`` are held at ``fixed`` (default: the paper start).
    """
    robot, default_scene, checker = core
    if scene is not None:
        checker.set_scene(scene)
    try:
        for a, b in zip(positions[:-1], positions[1:], strict=True):
            steps = max(1, int(math.ceil(np.max(np.abs(b - a)) / FINE_RESOLUTION)))
            for s in np.linspace(0.0, 1.0, steps + 1):
                state = dict(fixed or PAPER_START)
                state.update(zip(names, a + s * (b - a), strict=True))
                q = _full_q(robot, state)
                assert checker.is_valid(q), f"path collides at {state}: {checker.colliding_pairs(q)}"
    finally:
        if scene is not None:
            checker.set_scene(default_scene)


def _easy_goal(start: dict[str, float], delta: float = 0.3) -> dict[str, float]:
    """A right-arm move from the paper start that stays clear of the desk."""
    goal = dict(start)
    goal["r_arm_j4"] = start["r_arm_j4"] + delta
    return goal


def _plan(client, goal, start=None, **kwargs):
    kwargs.setdefault("time_budget", 5.0)
    kwargs.setdefault("seed", 7)
    return client.plan(goal, start=start if start is not None else PAPER_START, **kwargs)


def _good_request_still_succeeds(client, time_budget: float = 5.0):
    response = _plan(client, _easy_goal(PAPER_START), planner_id="RRTConnect", time_budget=time_budget)
    _assert_success(response)


# ---------------------------------------------------------------- state that must come first


def test_each_worker_process_warmed_its_kernels_up_at_configure(client, planner_node):
    log = planner_node.log()
    assert "worker process 0: kernels warmed up" in log and "worker process 1: kernels warmed up" in log, log


def test_empty_start_without_joint_states_is_no_start_state(client):
    response = client.plan(PAPER_GOAL, start=None, time_budget=2.0)
    assert response.error.code == _codes().NO_START_STATE
    assert "joint_states" in response.error.message


# ---------------------------------------------------------------- the paper problem


@pytest.mark.parametrize("planner_id", list(PAPER_SEEDS))
def test_plans_paper_problem_with_each_planner(client, core, planner_id):
    response = client.plan(
        _shuffled(PAPER_GOAL),
        start=_shuffled(PAPER_START),
        group="upper_body",
        planner_id=planner_id,
        time_budget=PAPER_BUDGET,
        seed=PAPER_SEEDS[planner_id],
        timeout=PAPER_BUDGET + 60.0,
    )
    _assert_plan_matches(core, response, planner_id, GROUP_JOINTS, PAPER_START, PAPER_GOAL)


def _assert_plan_matches(core, response, planner_id, joints, start, goal):
    _assert_success(response)
    names, times, positions = _positions(response)
    assert names == joints  # the group's order, whatever order the request used
    assert times[0] == 0.0 and np.all(np.diff(times) > 0)
    np.testing.assert_allclose(positions[0], [start[n] for n in names], atol=1e-6)
    np.testing.assert_allclose(positions[-1], [goal[n] for n in names], atol=1e-6)
    assert response.stats.planner_id == planner_id
    assert response.stats.collision_checks > 0 and response.stats.nodes > 0
    assert response.planning_time > 0
    _assert_path_free(core, names, positions, fixed=start)


ARM_JOINTS = GROUP_JOINTS[1:7]
# Paper 000's 6-DOF problem (arm stretched forward -> hanging down) for the right arm, waist at 0,
# left arm at the 13-DOF start.
ARM_START = dict(PAPER_START, waist_yaw=0.0, **dict(zip(ARM_JOINTS, (0.0, 1.57, 1.57, 0.0, -1.57, -1.57))))
ARM_GOAL = dict(zip(ARM_JOINTS, (-1.57, 1.57, 1.57, 0.0, -1.57, -1.57)))


def test_plans_the_paper_arm_problem_in_the_right_arm_group(client, core):
    """A smaller group by service: the paper's 6-DOF arm problem (RC-RRT) in the 13-DOF scene;
    the other joints stay where the start state has them."""
    response = client.plan(
        _shuffled(ARM_GOAL), start=_shuffled(ARM_START), group="right_arm", planner_id="RCRRT", time_budget=20.0, seed=2
    )
    _assert_plan_matches(core, response, "RCRRT", ARM_JOINTS, ARM_START, ARM_GOAL)


def test_plain_rrt_times_out_on_paper_problem_as_in_the_paper(client):
    """Paper 000 Table: RRT (no goal bias) failed on the 13-DOF problem; the node reports TIMED_OUT + stats."""
    response = client.plan(PAPER_GOAL, start=PAPER_START, planner_id="RRT", time_budget=2.0, seed=3)
    assert response.error.code == _codes().TIMED_OUT, response.error.message
    assert "RRT" in response.error.message
    assert response.stats.planner_id == "RRT" and response.stats.nodes > 0
    assert len(response.trajectory.points) == 0


# ---------------------------------------------------------------- pose goals, IK, /joint_states


def _hand_targets(robot, values: dict[str, float]) -> dict[str, np.ndarray]:
    q = _full_q(robot, values)
    return {frame: np.asarray(robot.frame_pose(q, frame)) for frame in robot.end_effectors.values()}


def test_pose_goals_are_solved_by_ik(client, core):
    robot = core[0]
    goal = _easy_goal(PAPER_START, 0.4)
    targets = _hand_targets(robot, goal)
    response = _plan(client, None, goal_poses=targets, planner_id="RRTConnect", time_budget=10.0)
    _assert_success(response)
    names, _, positions = _positions(response)
    reached = _hand_targets(robot, {**PAPER_START, **dict(zip(names, positions[-1], strict=True))})
    for frame, target in targets.items():
        np.testing.assert_allclose(reached[frame][:3, 3], target[:3, 3], atol=2e-3, err_msg=frame)
        np.testing.assert_allclose(reached[frame][:3, :3], target[:3, :3], atol=2e-2, err_msg=frame)
    _assert_path_free(core, names, positions)


def test_compute_ik_service(client, core):
    robot = core[0]
    goal = _easy_goal(PAPER_START, 0.4)
    target = _hand_targets(robot, goal)["r_hand"]
    response = client.compute_ik({"r_hand": target}, group="right_arm", seed=PAPER_START)
    _assert_success(response)
    solution = dict(zip(response.solution.name, response.solution.position, strict=True))
    reached = np.asarray(robot.frame_pose(_full_q(robot, solution), "r_hand"))
    np.testing.assert_allclose(reached[:3, 3], target[:3, 3], atol=2e-3)
    far = np.eye(4)
    far[:3, 3] = [3.0, 0.0, 0.0]
    response = client.compute_ik({"r_hand": far}, group="right_arm", seed=PAPER_START)
    assert response.error.code == _codes().NO_IK_SOLUTION and "r_hand" in response.error.message


def test_empty_start_uses_latest_joint_states(client, tester, joint_states):
    start = _easy_goal(PAPER_START, 0.2)  # differs from PAPER_START and the fixture's state
    goal = _easy_goal(PAPER_START, 0.5)
    response = _plan_from_joint_states(client, tester, joint_states, start, goal)
    _assert_success(response)
    names, _, positions = _positions(response)
    np.testing.assert_allclose(positions[0], [start[n] for n in names], atol=1e-6)


# ---------------------------------------------------------------- scene changes


def _straight_line_sphere(robot, start, goal) -> list[float]:
    """Where the right hand passes halfway along the straight joint-space line."""
    middle = {n: 0.5 * (start[n] + goal[n]) for n in start}
    return list(np.asarray(robot.frame_pose(_full_q(robot, middle), "r_hand"))[:3, 3])


def _straight(positions: np.ndarray) -> bool:
    """All waypoints on the segment from the first to the last (a straight joint-space path)."""
    a, b = positions[0], positions[-1]
    direction = (b - a) / np.linalg.norm(b - a)
    offsets = positions - a
    residual = offsets - np.outer(offsets @ direction, direction)
    return bool(np.max(np.linalg.norm(residual, axis=1)) < 1e-6)


def test_scene_changes_by_service_are_used_by_the_next_plan(client, core):
    from maru_planner.scene import Scene

    robot, scene, _ = core
    start = PAPER_START
    goal = dict(start, r_arm_j1=start["r_arm_j1"] + 0.9, r_arm_j4=start["r_arm_j4"] - 0.5)
    free = _plan(client, goal, planner_id="RRTConnect", time_budget=5.0)
    _assert_success(free)
    assert _straight(_positions(free)[2]), "with nothing in the way the simplified path should be straight"

    centre = _straight_line_sphere(robot, start, goal)
    pose = np.eye(4)
    pose[:3, 3] = centre
    added = client.add_obstacle("ball", "sphere", [0.06], pose)
    _assert_success(added)
    assert "ball" in added.obstacle_names
    assert "ball" in [o.name for o in client.get_scene().obstacles]

    blocked = _plan(client, goal, planner_id="RRTConnect", time_budget=10.0)
    _assert_success(blocked)
    names, _, positions = _positions(blocked)
    assert not _straight(positions), "the plan went straight through the new obstacle"
    with_ball = Scene.from_dict(scene.to_dict())
    with_ball_dict = with_ball.to_dict()
    with_ball_dict["obstacles"] = with_ball_dict.get("obstacles", []) + [
        o for o in Scene.from_yaml(client.get_scene().scene_yaml).to_dict()["obstacles"] if o["name"] == "ball"
    ]
    _assert_path_free(core, names, positions, scene=Scene.from_dict(with_ball_dict))

    removed = client.remove_obstacle("ball")
    _assert_success(removed)
    assert "ball" not in removed.obstacle_names
    again = _plan(client, goal, planner_id="RRTConnect", time_budget=5.0)
    _assert_success(again)
    assert _straight(_positions(again)[2])


def test_scene_topic_adds_and_removes_obstacles(client, tester):
    from maru_planner.ros.planning_client import obstacle_msg
    from maru_planner_interfaces.msg import SceneObstacle

    publisher = tester.node.create_publisher(SceneObstacle, "/planning_scene_obstacles", 10)
    pose = np.eye(4)
    pose[:3, 3] = [-1.0, 0.0, 0.0]
    message = obstacle_msg("behind", "box", [0.1, 0.1, 0.1], pose)
    assert tester.wait_for(lambda: publisher.get_subscription_count() > 0, timeout=60.0)

    def listed() -> bool:
        return "behind" in [o.name for o in client.get_scene().obstacles]

    # Until the node has matched this new publisher what it sends is lost: send until it shows. A repeated
    # ADD replaces the same box; one writer's messages arrive in order, so none can land after the REMOVE.
    assert _publish_until(tester, publisher, message, listed), "the ADD never reached the scene"
    publisher.publish(SceneObstacle(name="behind", operation=SceneObstacle.REMOVE))
    assert tester.wait_for(lambda: not listed(), timeout=30.0)


def _publish_until(tester, publisher, message, condition, timeout: float = 60.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        publisher.publish(message)
        if tester.wait_for(condition, timeout=min(1.0, max(deadline - time.monotonic(), 0.0)), period=0.05):
            return True
    return False


# ---------------------------------------------------------------- bad input


def _in_collision_with_desk(core) -> dict[str, float]:
    """A right-arm configuration touching the desk (sampled, confirmed by the core checker)."""
    robot, _, checker = core
    rng = np.random.default_rng(0)
    arm = robot.joint_indices(GROUP_JOINTS[1:7])
    for _ in range(5000):
        values = dict(PAPER_START)
        values.update(
            zip(GROUP_JOINTS[1:7], rng.uniform(robot.lower_limits[arm], robot.upper_limits[arm]), strict=True)
        )
        pairs = checker.colliding_pairs(_full_q(robot, values))
        if any("desk" in a or "desk" in b for a, b in pairs):
            return values
    raise AssertionError("no configuration touching the desk found")


BAD_PLANS = {
    "unknown planner": (dict(planner_id="FooPlanner"), "INVALID_PLANNER", "FooPlanner"),
    "unknown group": (dict(group="tail"), "INVALID_GROUP_NAME", "tail"),
    "wrong joint names": (dict(goal={**PAPER_GOAL, "r_arm_j9": 0.1}), "INVALID_JOINT_NAMES", "r_arm_j9"),
    "wrong count": (
        dict(goal={k: v for k, v in PAPER_GOAL.items() if k != "l_arm_j3"}),
        "INVALID_JOINT_COUNT",
        "l_arm_j3",
    ),
    "NaN": (dict(goal={**PAPER_GOAL, "r_arm_j2": math.nan}), "INVALID_ROBOT_STATE", "r_arm_j2"),
    "out of limits": (dict(start={**PAPER_START, "r_arm_j4": 10.0}), "INVALID_ROBOT_STATE", "r_arm_j4"),
    "zero time budget": (dict(time_budget=0.0), "INVALID_REQUEST", "allowed_planning_time"),
    "negative time budget": (dict(time_budget=-1.0), "INVALID_REQUEST", "allowed_planning_time"),
}


@pytest.mark.parametrize("case", list(BAD_PLANS))
def test_bad_plan_request_is_answered_and_node_keeps_serving(client, case):
    fields, code, culprit = BAD_PLANS[case]
    fields = dict(fields)
    goal = fields.pop("goal", PAPER_GOAL)
    start = fields.pop("start", PAPER_START)
    response = client.plan(goal, start=start, **{"time_budget": 2.0, **fields})
    assert response.error.code == getattr(_codes(), code), response.error.message
    assert culprit in response.error.message
    assert len(response.trajectory.points) == 0
    _good_request_still_succeeds(client)


def test_start_in_collision(client, core):
    colliding = _in_collision_with_desk(core)
    response = client.plan(PAPER_GOAL, start=colliding, time_budget=2.0)
    assert response.error.code == _codes().START_STATE_IN_COLLISION, response.error.message
    assert "desk" in response.error.message
    _good_request_still_succeeds(client)


def test_goal_in_collision(client, core):
    colliding = _in_collision_with_desk(core)
    response = client.plan(colliding, start=PAPER_START, time_budget=2.0)
    assert response.error.code == _codes().GOAL_IN_COLLISION, response.error.message
    assert "desk" in response.error.message
    _good_request_still_succeeds(client)


def test_unreachable_pose(client):
    far = np.eye(4)
    far[:3, 3] = [3.0, -0.2, 0.2]
    response = _plan(client, None, goal_poses={"r_hand": far}, time_budget=3.0)
    assert response.error.code == _codes().NO_IK_SOLUTION, response.error.message
    assert "r_hand" in response.error.message
    _good_request_still_succeeds(client)


def test_malformed_obstacle_leaves_scene_unchanged(client):
    from maru_planner.ros.planning_client import obstacle_msg

    before = [o.name for o in client.get_scene().obstacles]
    good = obstacle_msg("ok_box", "box", [0.1, 0.1, 0.1], np.eye(4))
    bad = obstacle_msg("crate", "box", [0.1, 0.1], np.eye(4))
    response = client.apply_scene([good, bad])
    assert response.error.code == _codes().INVALID_SCENE
    assert "crate" in response.error.message
    assert [o.name for o in client.get_scene().obstacles] == before  # all-or-nothing
    elsewhere = obstacle_msg("far_box", "box", [0.1, 0.1, 0.1], np.eye(4), frame_id="map")
    response = client.apply_scene([elsewhere])
    assert response.error.code == _codes().INVALID_SCENE and "'map'" in response.error.message
    response = client.remove_obstacle("no_such_thing")
    assert response.error.code == _codes().INVALID_SCENE and "no_such_thing" in response.error.message
    _good_request_still_succeeds(client)


# ---------------------------------------------------------------- concurrency and robustness


def test_eight_concurrent_clients_each_get_their_own_answer(planner_node, tester):
    from maru_planner.ros.planning_client import call_until_answered, plan_request
    from maru_planner_interfaces.srv import PlanMotion

    node = tester.node
    clients = [node.create_client(PlanMotion, "plan_motion") for _ in range(8)]
    for c in clients:
        assert c.wait_for_service(timeout_sec=60.0)
        call_until_answered(c, PlanMotion.Request(), timeout=60.0)  # an empty request: INVALID_REQUEST at once
    goals = [_easy_goal(PAPER_START, 0.05 * (i + 1)) for i in range(8)]
    futures = [
        c.call_async(plan_request(g, start=PAPER_START, planner_id="RRTConnect", time_budget=10.0, seed=i))
        for i, (c, g) in enumerate(zip(clients, goals, strict=True))
    ]
    assert tester.wait_for(lambda: all(f.done() for f in futures), timeout=120.0)
    for goal, future in zip(goals, futures, strict=True):
        response = future.result()
        _assert_success(response)
        names, _, positions = _positions(response)
        np.testing.assert_allclose(positions[-1], [goal[n] for n in names], atol=1e-6)


def test_a_long_plan_does_not_block_joint_states_or_scene_updates(client, tester, joint_states):
    """While an RRT search runs (it cannot solve the paper problem, so it uses its whole budget),
    scene services answer and /joint_states are taken in; a plan sent meanwhile starts from them.

    ``joint_states`` is already matched by the node, and the three service calls after publishing
    come back only after the node has taken in the joint states sent before them."""
    from maru_planner.ros.planning_client import plan_request

    long_plan = client.plan_client.call_async(
        plan_request(PAPER_GOAL, start=PAPER_START, planner_id="RRT", time_budget=8.0, seed=5)
    )
    time.sleep(0.3)
    moved = _easy_goal(PAPER_START, 0.15)
    _publish_state(tester, joint_states, moved, times=5)
    pose = np.eye(4)
    pose[:3, 3] = [-1.0, -0.5, 0.3]
    added = client.add_obstacle("meanwhile", "sphere", [0.05], pose)
    listed = [o.name for o in client.get_scene().obstacles]
    removed = client.remove_obstacle("meanwhile")
    assert not long_plan.done(), "the long plan ended before the checks ran; they proved nothing"
    _assert_success(added)
    _assert_success(removed)
    assert "meanwhile" in listed
    follow_up = client.plan_client.call_async(
        plan_request(_easy_goal(PAPER_START, 0.4), planner_id="RRTConnect", time_budget=10.0, seed=2)
    )
    assert not long_plan.done()
    assert tester.wait_for(lambda: long_plan.done() and follow_up.done(), timeout=120.0)
    assert long_plan.result().error.code == _codes().TIMED_OUT
    names, _, positions = _positions(follow_up.result())
    np.testing.assert_allclose(positions[0], [moved[n] for n in names], atol=1e-9)


DISCONNECTING_CLIENT = textwrap.dedent(
    """
    import sys, time
    from maru_planner.ros.env import configure_loopback_dds
    configure_loopback_dds()
    import rclpy
    from maru_planner.ros.planning_client import PlanningClient, plan_request
    rclpy.init()
    client = PlanningClient(node_name="leaving_client")
    goal = dict(zip({names!r}, {goal!r}))
    start = dict(zip({names!r}, {start!r}))
    client.wait_until_ready(timeout=60.0)  # both directions matched: the call below reaches the node
    client.plan_client.call_async(plan_request(goal, start=start, planner_id="RRT", time_budget=4.0))
    print("sent", flush=True)
    time.sleep(1.0)
    import os
    os._exit(0)  # vanish mid-call, without a clean shutdown
    """
)


def test_survives_a_client_that_disconnects_mid_call(client, tester, planner_node):
    script = DISCONNECTING_CLIENT.format(
        names=GROUP_JOINTS, goal=[PAPER_GOAL[n] for n in GROUP_JOINTS], start=[PAPER_START[n] for n in GROUP_JOINTS]
    )
    timed_out = planner_node.log().count("plan_motion: TIMED_OUT")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=180)
    assert "sent" in result.stdout, result.stderr
    # the abandoned plan (RRT cannot solve it) runs out its budget and its answer goes nowhere
    ended = tester.wait_for(lambda: planner_node.log().count("plan_motion: TIMED_OUT") > timed_out, 60.0, 0.1)
    assert ended, "the abandoned plan never ended:\n" + planner_node.log()[-2000:]
    assert planner_node.alive(), planner_node.log()
    _good_request_still_succeeds(client)


def test_trajectory_and_markers_are_published(client, tester):
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from trajectory_msgs.msg import JointTrajectory
    from visualization_msgs.msg import MarkerArray

    trajectories, markers = [], []
    node = tester.node
    # Latched like the node's publisher: even if the node matches this reader only after publishing
    # the plan, the reader still gets it. An older plan may come first; the wait below picks ours.
    latched = QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(JointTrajectory, f"{NODE}/planned_trajectory", trajectories.append, latched)
    node.create_subscription(MarkerArray, f"{NODE}/markers", markers.append, 10)
    assert tester.wait_for(lambda: node.count_publishers(f"{NODE}/markers") > 0, timeout=60.0)
    # the node greets a new subscriber with the scene (so it has matched this reader: nothing later is lost)
    assert tester.wait_for(lambda: markers, timeout=60.0)
    response = _plan(client, _easy_goal(PAPER_START, 0.35), planner_id="RRTConnect")
    _assert_success(response)
    stamp = response.trajectory.header.stamp

    def ours(msg) -> bool:
        return msg.header.stamp == stamp

    def plan_markers_of_ours() -> bool:
        return any(mk.ns == "hand_path" and ours(mk) for m in markers for mk in m.markers)

    assert tester.wait_for(lambda: any(ours(t) for t in trajectories) and plan_markers_of_ours(), 60.0)
    last = [t for t in trajectories if ours(t)][-1]
    assert list(last.joint_names) == list(response.trajectory.joint_names)
    assert len(last.points) == len(response.trajectory.points)
    spaces = set().union(*(_namespaces(m) for m in markers))
    assert {"scene", "hand_path"} <= spaces
    scene_names = {mk.text for m in markers for mk in m.markers if mk.ns == "scene"}
    assert {o.name for o in client.get_scene().obstacles} <= scene_names


def _namespaces(marker_array) -> set[str]:
    return {m.ns for m in marker_array.markers if m.ns}


# ---------------------------------------------------------------- load and hostile topics (issue 18)

BURST = 64
ROUNDS = 5


def test_64_clients_5_rounds_lose_nothing_and_no_busy_when_the_work_fits(planner_node, tester, client):
    """64 clients call plan_motion at once, 5 rounds (issue 36): every call answered, none BUSY.

    Every client's response reader sees the answers to all 64 (Fast DDS: one reply topic per service); the
    clients use planning_client.REPLY_QOS (depth 256), as PlanningClient does, so none evicts its own answer.
    Each round fits its budgets (64 short plans on 2 workers), so admission by expected wait refuses none."""
    from maru_planner.ros.planning_client import REPLY_QOS, call_until_answered, plan_request, send_request
    from maru_planner_interfaces.srv import PlanMotion

    node = tester.node
    clients = [node.create_client(PlanMotion, "plan_motion", qos_profile=REPLY_QOS) for _ in range(BURST)]
    for c in clients:
        assert c.wait_for_service(timeout_sec=60.0)
        call_until_answered(c, PlanMotion.Request(), timeout=60.0)  # both directions matched: nothing lost there
    budget = 20.0  # generous: admission by expected wait must not refuse a round even on a loaded machine
    lost, codes = [], []
    for round_ in range(ROUNDS):
        calls = [
            send_request(c, plan_request(_easy_goal(PAPER_START, 0.2 + 0.002 * i), start=PAPER_START,
                                         time_budget=budget, seed=round_))
            for i, c in enumerate(clients)
        ]  # fmt: skip
        tester.wait_for(lambda calls=calls: all(call.future.done() for call in calls), timeout=budget + 60.0)
        lost.append(sum(not call.future.done() for call in calls))
        codes += [call.future.result().error.code for call in calls if call.future.done()]
        assert len({(call.client, call.request_id) for call in calls}) == BURST  # each call its own id
    log = planner_node.log()
    assert sum(lost) == 0, (
        f"{sum(lost)} of {BURST * ROUNDS} requests never answered (per round {lost}); the node answered "
        f"{log.count('plan_motion: BUSY')} BUSY and {log.count('points, core')} plans in all"
    )
    assert codes.count(_codes().SUCCESS) == BURST * ROUNDS, sorted(set(codes))
    for c in clients:
        node.destroy_client(c)
    _good_request_still_succeeds(client)


def test_junk_joint_states_are_ignored_and_counted_never_stored(client, tester, joint_states, planner_node):
    """A gripper joint, 50k junk names and NaN values on /joint_states: the robot's joints are still
    taken from it, nothing else is kept (memory stays flat), and an empty start plans from the real joints."""
    from sensor_msgs.msg import JointState

    moved = _easy_goal(PAPER_START, 0.12)
    with_gripper = dict(moved, r_gripper_finger_joint=0.04)
    # taken (the plan starts there) before the burst: a burst on a loaded machine may drop a message queued before it
    _assert_success(_plan_from_joint_states(client, tester, joint_states, with_gripper, _easy_goal(PAPER_START, 0.3)))
    rss_before = rss_mb(planner_node.proc.pid)
    junk = JointState(name=[f"junk_{i}" for i in range(50_000)], position=[0.0] * 50_000)
    for _ in range(20):
        joint_states.publish(junk)
    joint_states.publish(JointState(name=list(moved), position=[math.nan] * len(moved)))
    joint_states.publish(JointState(name=["waist_yaw"], position=[0.1, 0.2]))  # mismatched lengths
    response = _plan_from_joint_states(client, tester, joint_states, moved, _easy_goal(PAPER_START, 0.35))
    _assert_success(response)
    assert _starts_at(response, moved)
    assert "r_gripper_finger_joint" in planner_node.log() and "so far" in planner_node.log()
    assert rss_mb(planner_node.proc.pid) - rss_before < 50.0


def _children(pid: int) -> list[int]:
    children = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parent = int(stat.read_text().rsplit(") ", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):  # a process that ended meanwhile
            continue
        if parent == pid:
            children.append(int(stat.parent.name))
    return children


def _worker_pids(node_pid: int) -> list[int]:
    """The node's planning worker processes: the children of its multiprocessing fork server."""
    servers = [p for p in _children(node_pid) if b"forkserver" in Path(f"/proc/{p}/cmdline").read_bytes()]
    return sorted(worker for server in servers for worker in _children(server))


def test_a_killed_planning_worker_fails_its_goal_at_once_and_is_replaced(client, planner_node):
    """SIGKILL to the worker processes while one plans a goal: the goal ends PLANNING_FAILED naming the worker and
    the signal long before its budget, new workers replace them and the next request plans."""
    workers = _worker_pids(planner_node.proc.pid)
    assert len(workers) == 2, workers  # planner.yaml: workers 2
    searching = threading.Event()
    goal = client.plan_action(
        PAPER_GOAL, start=PAPER_START, planner_id="RRT", time_budget=60.0, seed=3,
        feedback_callback=lambda feedback: feedback.stage == "search" and searching.set(),
    )  # fmt: skip
    assert searching.wait(60.0), "the goal never reached a worker's search"
    for pid in workers:  # the goal's worker among them
        os.kill(pid, signal.SIGKILL)
    _, result = goal.result(timeout=30.0)  # far below the 60 s budget
    assert result.error.code == _codes().PLANNING_FAILED, result.error.message
    killed = r"the planning worker (\d+) died \(signal 9, SIGKILL\) while planning; it was restarted"
    match = re.search(killed, result.error.message)
    assert match and int(match.group(1)) in workers, result.error.message
    _good_request_still_succeeds(client, time_budget=30.0)  # it waits for a replacement's start on a loaded machine
    replacements = _worker_pids(planner_node.proc.pid)
    assert len(replacements) == 2 and not set(replacements) & set(workers), (workers, replacements)
