"""Planning as a ROS 2 action: one :class:`~maru_planner.monitor.PlanMonitor` per goal (both planner nodes).

:class:`PlanActionServer` accepts every goal (a managed node, :mod:`maru_planner.ros.lifecycle`,
accepts them only while active), gives it a monitor and runs the node's plan coroutine with it.
While the goal runs, a timer publishes the monitor's snapshot as feedback; a cancel request cancels
the monitor, which stops the planner at once. The goal ends SUCCEEDED (the node's
``succeeded(result)``), CANCELED (cancelled and not successful) or ABORTED, always with the result
the plan coroutine returned (the node's service response, as an action result).
"""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable
from typing import Any

from rclpy.action import ActionServer, CancelResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from rclpy.qos import QoSProfile, qos_profile_services_default

from maru_planner.monitor import PlanMonitor, Progress

CANCEL_SETTLE_TIMEOUT = 1.0  # s a finished goal waits for rclpy to mark its accepted cancel (microseconds in practice)


class PlanActionServer:
    """An ``rclpy.action.ActionServer`` whose goals are plans watched and cancelled through a PlanMonitor.

    ``plan(goal, monitor)`` is the node's coroutine answering a goal (it must not raise: failures are
    part of its result); ``feedback(progress)`` makes a feedback message; ``period()`` is the feedback
    period in seconds, read when a goal starts. Callbacks run in ``callback_group`` (reentrant, so that
    feedback and cancel requests are served while a plan is awaited).
    """

    def __init__(
        self,
        node: Node,
        action_type: Any,
        name: str,
        *,
        plan: Callable[[Any, PlanMonitor], Awaitable[Any]],
        succeeded: Callable[[Any], bool],
        feedback: Callable[[Progress], Any],
        period: Callable[[], float],
        callback_group: CallbackGroup,
        requests_qos: QoSProfile = qos_profile_services_default,
    ):
        self._node = node
        self._plan = plan
        self._succeeded = succeeded
        self._feedback = feedback
        self._period = period
        self._callback_group = callback_group
        self._monitors: dict[bytes, PlanMonitor] = {}
        self.server = ActionServer(
            node,
            action_type,
            name,
            self._execute,
            callback_group=callback_group,
            handle_accepted_callback=self._on_accepted,
            cancel_callback=self._on_cancel,
            goal_service_qos_profile=requests_qos,
            result_service_qos_profile=requests_qos,
        )

    @property
    def running_goals(self) -> int:
        """Goals accepted and not finished (waiting for a worker or planning)."""
        return len(self._monitors)

    def _on_accepted(self, goal_handle: ServerGoalHandle) -> None:
        """Every goal is accepted (its result says what was wrong); its monitor exists before a cancel can come."""
        self._monitors[bytes(goal_handle.goal_id.uuid)] = PlanMonitor()
        goal_handle.execute()

    def _on_cancel(self, goal_handle: ServerGoalHandle) -> CancelResponse:
        monitor = self._monitors.get(bytes(goal_handle.goal_id.uuid))
        if monitor is not None:
            monitor.cancel()
        return CancelResponse.ACCEPT

    async def _execute(self, goal_handle: ServerGoalHandle) -> Any:
        key = bytes(goal_handle.goal_id.uuid)
        monitor = self._monitors[key]

        def publish_feedback() -> None:
            goal_handle.publish_feedback(self._feedback(monitor.snapshot()))

        publish_feedback()
        timer = self._node.create_timer(self._period(), publish_feedback, callback_group=self._callback_group)
        try:
            result = await self._plan(goal_handle.request, monitor)
        finally:
            self._node.destroy_timer(timer)
            del self._monitors[key]
        if self._succeeded(result):
            goal_handle.succeed()
        elif monitor.cancelled and _cancel_settled(goal_handle):
            goal_handle.canceled()
        else:
            goal_handle.abort()
        return result


def _cancel_settled(goal_handle: ServerGoalHandle) -> bool:
    """Whether the goal is CANCELING (only then may it end CANCELED).

    The cancel callback stops the plan before rclpy marks the goal CANCELING, so a plan that stops at
    once may finish first; the mark follows within microseconds on the cancelling executor thread.
    """
    deadline = time.monotonic() + CANCEL_SETTLE_TIMEOUT
    while not goal_handle.is_cancel_requested and time.monotonic() < deadline:
        time.sleep(0.0005)
    return goal_handle.is_cancel_requested
