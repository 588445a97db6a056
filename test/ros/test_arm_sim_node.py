"""arm_sim_node in its own process (Maru-1, no obstacles): /joint_states at its rate, a trajectory executed through
the execute_trajectory action with feedback and a SUCCESSFUL result, a tolerance violation ABORTED with its code,
bad goals refused with INVALID_JOINTS / INVALID_GOAL, a cancel that leaves the arm at rest, and Ctrl-C (SIGINT) while
it publishes at 250 Hz a quiet exit. One node for the module (the last test stops it).
"""

from __future__ import annotations

import signal
import threading
import time

import numpy as np
import pytest
from builtin_interfaces.msg import Duration
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from maru_planner.execution.tolerances import ResultCode
from maru_planner.paths import config_path
from maru_planner.ros.plan_actions import DrainingActionClient as ActionClient
from maru_planner_interfaces.action import ExecuteTrajectory
from maru_planner_interfaces.msg import JointTolerance

pytestmark = pytest.mark.ros
R = ExecuteTrajectory.Result


class States:
    def __init__(self):
        self.lock = threading.Lock()
        self.messages: list[tuple[float, JointState]] = []

    def __call__(self, msg: JointState) -> None:
        with self.lock:
            self.messages.append((time.monotonic(), msg))

    def latest(self) -> JointState | None:
        with self.lock:
            return self.messages[-1][1] if self.messages else None


@pytest.fixture(scope="module")
def arm(node_process, tester):
    proc = node_process(
        "maru_planner.ros.arm_sim_node", ["--ros-args", "--params-file", str(config_path("arm_sim.yaml"))]
    )
    states = States()
    tester.node.create_subscription(JointState, "joint_states", states, 50)
    client = ActionClient(tester.node, ExecuteTrajectory, "execute_trajectory")
    assert client.wait_for_server(timeout_sec=60.0), "execute_trajectory never appeared:\n" + proc.log()
    assert tester.wait_for(lambda: states.latest() is not None, timeout=30.0), proc.log()
    yield client, states, proc
    assert proc.alive() or proc.proc.returncode == 0, "arm_sim_node died:\n" + proc.log()  # the last test stops it


def _trajectory(names, start, offsets, duration=1.0) -> JointTrajectory:
    """Cubic: rest to rest from ``start`` by ``offsets`` over ``duration`` (three points)."""
    msg = JointTrajectory(joint_names=list(names))
    middle, end = start + 0.5 * offsets, start + offsets
    speed = 1.5 * offsets / duration  # a smooth-step's peak
    for t, q, v in ((0.0, start, 0 * offsets), (0.5 * duration, middle, speed), (duration, end, 0 * offsets)):
        stamp = Duration(sec=int(t), nanosec=int(round((t - int(t)) * 1e9)))
        msg.points.append(JointTrajectoryPoint(positions=q.tolist(), velocities=v.tolist(), time_from_start=stamp))
    return msg


def _send(tester, client, goal, feedback=None, timeout=30.0):
    future = client.send_goal_async(goal, feedback_callback=feedback)
    assert tester.wait_for(future.done, timeout=timeout)
    handle = future.result()
    assert handle.accepted
    return handle


def _result(tester, handle, timeout=30.0):
    future = handle.get_result_async()
    assert tester.wait_for(future.done, timeout=timeout)
    return future.result()


def _here(states) -> tuple[list[str], np.ndarray]:
    msg = states.latest()
    return list(msg.name), np.array(msg.position)


def test_joint_states_are_published_at_250_hz(arm, tester):
    _, states, _ = arm
    with states.lock:
        first = len(states.messages)
    time.sleep(1.0)
    with states.lock:
        window = [msg for _, msg in states.messages[first:]]
    stamps = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in window])
    assert len(window) >= 50  # alive; a machine loaded by other suites may delay some ticks
    assert 0.002 <= np.median(np.diff(stamps)) <= 0.006  # the 4 ms tick (delayed ticks catch up)
    msg = window[-1]
    assert len(msg.name) == 13 and len(msg.position) == len(msg.velocity) == len(msg.effort) == 13


def test_a_trajectory_is_executed_with_feedback(arm, tester):
    client, states, _ = arm
    names, here = _here(states)
    offsets = np.zeros(len(names))
    offsets[[1, 2, 8]] = [0.3, -0.2, 0.25]
    feedback: list = []
    handle = _send(
        tester, client, ExecuteTrajectory.Goal(trajectory=_trajectory(names, here, offsets)), feedback.append
    )
    response = _result(tester, handle)
    result = response.result
    assert result.error_code == R.SUCCESSFUL, result.error_string
    assert response.status == 4  # GoalStatus.STATUS_SUCCEEDED
    assert result.max_tracking_error <= 0.02 and 0.0 <= result.overrun <= 0.05
    assert list(result.contact_links) == []
    assert len(feedback) >= 15  # >= 20 Hz over a 1 s trajectory (25 Hz nominal)
    last = feedback[-1].feedback
    assert list(last.joint_names) == names and len(last.error.positions) == len(names)
    assert tester.wait_for(lambda: np.allclose(_here(states)[1], here + offsets, atol=0.01), timeout=5.0)


def test_a_path_tolerance_violation_aborts_with_its_code(arm, tester):
    client, states, _ = arm
    names, here = _here(states)
    offsets = np.zeros(len(names))
    offsets[3] = 0.3
    tight = [JointTolerance(name=names[3], position=1e-5)]
    goal = ExecuteTrajectory.Goal(trajectory=_trajectory(names, here, offsets), path_tolerance=tight)
    response = _result(tester, _send(tester, client, goal))
    assert response.result.error_code == R.PATH_TOLERANCE_VIOLATED
    assert names[3] in response.result.error_string and response.status == 6  # ABORTED


def test_bad_goals_are_refused_with_their_codes(arm, tester):
    client, states, _ = arm
    names, here = _here(states)
    renamed = _trajectory(["elbow", *names[1:]], here, np.zeros(len(names)))
    assert _result(tester, _send(tester, client, ExecuteTrajectory.Goal(trajectory=renamed))).result.error_code == (
        R.INVALID_JOINTS
    )
    far = _trajectory(names, here + 0.2, np.zeros(len(names)))
    result = _result(tester, _send(tester, client, ExecuteTrajectory.Goal(trajectory=far))).result
    assert result.error_code == R.INVALID_GOAL and "start tolerance" in result.error_string
    backwards = _trajectory(names, here, np.zeros(len(names)))
    backwards.points[2].time_from_start = Duration(sec=0, nanosec=100_000_000)
    result = _result(tester, _send(tester, client, ExecuteTrajectory.Goal(trajectory=backwards))).result
    assert result.error_code == R.INVALID_GOAL and "does not increase" in result.error_string
    broken = _trajectory(names, here, np.zeros(len(names)))
    broken.points[1].positions = [float("nan")] * len(names)
    result = _result(tester, _send(tester, client, ExecuteTrajectory.Goal(trajectory=broken))).result
    assert result.error_code == R.INVALID_GOAL and "NaN" in result.error_string
    broken.points[1].positions = list(here[:3])
    result = _result(tester, _send(tester, client, ExecuteTrajectory.Goal(trajectory=broken))).result
    assert result.error_code == R.INVALID_GOAL and "3 positions for 13 joints" in result.error_string
    partial = _trajectory(names[:2], here[:2], np.zeros(2))
    stray = [JointTolerance(name=names[5], position=0.1)]
    goal = ExecuteTrajectory.Goal(trajectory=partial, goal_tolerance=stray)
    assert _result(tester, _send(tester, client, goal)).result.error_code == R.INVALID_JOINTS
    old = _trajectory(names, here, np.zeros(len(names)))
    old.header.stamp = tester.node.get_clock().now().to_msg()
    old.header.stamp.sec -= 10  # a 1 s trajectory that started 10 s ago
    assert _result(tester, _send(tester, client, ExecuteTrajectory.Goal(trajectory=old))).result.error_code == (
        R.OLD_HEADER_TIMESTAMP
    )


def test_cancel_leaves_the_arm_at_rest(arm, tester):
    client, states, _ = arm
    names, here = _here(states)
    offsets = np.zeros(len(names))
    offsets[[0, 7]] = [0.5, -0.6]
    handle = _send(tester, client, ExecuteTrajectory.Goal(trajectory=_trajectory(names, here, offsets, 2.0)))
    time.sleep(0.8)
    cancel = handle.cancel_goal_async()
    assert tester.wait_for(cancel.done, timeout=10.0)
    response = _result(tester, handle)
    assert response.status == 5  # CANCELED
    assert tester.wait_for(lambda: np.max(np.abs(states.latest().velocity)) < 1e-3, timeout=5.0)
    _, rest = _here(states)
    assert 0.05 < abs(rest[0] - here[0]) < 0.5  # stopped part-way


def test_result_codes_are_the_core_codes():
    assert {code.name: int(code) for code in ResultCode} == {
        name: getattr(R, name) for name in dir(R) if name.isupper() and isinstance(getattr(R, name), int)
    }


def test_a_new_goal_preempts_the_running_one(arm, tester):
    client, states, _ = arm
    names, here = _here(states)
    offsets = np.zeros(len(names))
    offsets[[0, 7]] = [-0.3, 0.3]
    first = _send(tester, client, ExecuteTrajectory.Goal(trajectory=_trajectory(names, here, offsets, 2.0)))
    time.sleep(0.3)
    _, now = _here(states)
    wrist = [names[5]]  # a joint the first goal holds still: its start state is known exactly
    second = _send(
        tester, client, ExecuteTrajectory.Goal(trajectory=_trajectory(wrist, now[[5]], np.array([0.2]), 0.5))
    )
    preempted = _result(tester, first)
    assert preempted.status == 6 and preempted.result.error_code == R.INVALID_GOAL  # ABORTED
    assert "preempted" in preempted.result.error_string
    assert _result(tester, second).result.error_code == R.SUCCESSFUL


def test_sigint_stops_the_node_without_a_traceback(arm):
    """The physics thread publishes at 250 Hz: it must stop before the context and the publisher go."""
    _, _, proc = arm
    assert proc.alive(), proc.log()
    proc.proc.send_signal(signal.SIGINT)
    proc.wait_stopped()
    assert proc.proc.returncode == 0 and "Traceback" not in proc.log(), proc.log()
