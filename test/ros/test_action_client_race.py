"""DrainingActionClient has none of rclpy's lost-response race (ros2/rclpy#1123).

rclpy's ActionClient sends a goal, cancel or result request and only then records its sequence number; a response
an executor thread takes in between is dropped ("Ignoring unexpected goal response") and the caller waits forever.
The test widens that window: the client's handle pauses after each send, as a preempted caller thread would, while
an executor thread spins the client and a server in this process answers at once. rclpy's own client is the
control: it loses the goal response in the same set-up, so the test can see the race (and says when an rclpy
upgrade fixed it).
"""

from __future__ import annotations

import threading
import time

import pytest

pytestmark = pytest.mark.ros

PAUSE = 0.3  # s between a request's send and its recording (the widened window)


class _PausingHandle:
    """An rclpy action client handle that waits ``PAUSE`` after sending each request."""

    def __init__(self, handle):
        self._handle = handle

    def __getattr__(self, name: str):
        attribute = getattr(self._handle, name)
        if not name.startswith("send_"):
            return attribute

        def send_then_pause(request):
            sequence_number = attribute(request)
            time.sleep(PAUSE)
            return sequence_number

        return send_then_pause

    def __enter__(self):
        return self._handle.__enter__()

    def __exit__(self, *exc):
        return self._handle.__exit__(*exc)


@pytest.fixture
def served(rclpy_session, spinning_node):
    """An ExecuteTrajectory server answering every goal at once, spun with the test's client node."""
    from rclpy.action import ActionServer

    from maru_planner_interfaces.action import ExecuteTrajectory

    def succeed(goal_handle):
        goal_handle.succeed()
        return ExecuteTrajectory.Result()

    server = ActionServer(spinning_node.node, ExecuteTrajectory, "race_execute", succeed)
    yield spinning_node
    server.destroy()


def _send_goal(client_class, spinning) -> bool:
    """Whether a goal sent through a pausing ``client_class`` comes back with its goal response."""
    from maru_planner_interfaces.action import ExecuteTrajectory

    client = client_class(spinning.node, ExecuteTrajectory, "race_execute")
    try:
        assert client.wait_for_server(timeout_sec=30.0)
        client._client_handle = _PausingHandle(client._client_handle)
        answered = threading.Event()
        client.send_goal_async(ExecuteTrajectory.Goal()).add_done_callback(lambda _future: answered.set())
        return answered.wait(5.0)
    finally:
        client._client_handle = getattr(client._client_handle, "_handle", client._client_handle)
        client.destroy()


def test_a_goal_response_taken_before_the_send_returns_still_completes_the_future(served):
    from maru_planner.ros.plan_actions import DrainingActionClient

    assert _send_goal(DrainingActionClient, served), "the goal response was lost"


def test_rclpy_own_client_loses_that_response_so_the_test_can_see_the_race(served):
    from rclpy.action import ActionClient

    assert not _send_goal(ActionClient, served), (
        "rclpy's pinned ActionClient no longer loses the response (ros2/rclpy#1123 fixed): DrainingActionClient's "
        "lock can go, and this control with it"
    )
