"""Planning as a ROS 2 action: one :class:`~maru_planner.monitor.PlanMonitor` per goal (both planner nodes).

:class:`PlanActionServer` accepts every goal (a managed node, :mod:`maru_planner.ros.lifecycle`,
accepts them only while active), gives it a monitor and runs the node's plan coroutine with it.
While goals run, one timer publishes each running goal's monitor snapshot as feedback (one callback for all
goals, not a timer per goal: a storm of 32 goals costs the executor one wake-up per period); a cancel request
cancels the monitor, which stops the planner at once -- or, for a goal still waiting for a worker, ends it at
once (:meth:`~maru_planner.runtime.PlanningRuntime.plan`). The goal ends SUCCEEDED (the node's
``succeeded(result)``), CANCELED (cancelled and not successful) or ABORTED, always with the result
the plan coroutine returned (the node's service response, as an action result).
"""

from __future__ import annotations

import threading
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
        self._running: dict[bytes, tuple[ServerGoalHandle, PlanMonitor]] = {}  # executing: feedback goes out
        self._running_lock = threading.Lock()  # goals start and end on several executor threads
        self._feedback_timer = node.create_timer(period(), self._publish_feedback, callback_group=callback_group)
        self._feedback_timer.cancel()  # runs only while goals do
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
            cancel_service_qos_profile=requests_qos,  # a storm of cancels: rclpy's depth 10 dropped some
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

    def _publish_feedback(self) -> None:
        with self._running_lock:
            running = list(self._running.values())
        for goal_handle, monitor in running:
            goal_handle.publish_feedback(self._feedback(monitor.snapshot()))

    async def _execute(self, goal_handle: ServerGoalHandle) -> Any:
        key = bytes(goal_handle.goal_id.uuid)
        monitor = self._monitors[key]
        goal_handle.publish_feedback(self._feedback(monitor.snapshot()))
        with self._running_lock:
            self._running[key] = (goal_handle, monitor)
            if len(self._running) == 1:  # the first goal running: (re)start the timer at the period of now
                self._feedback_timer.timer_period_ns = int(self._period() * 1e9)
                self._feedback_timer.reset()
        try:
            result = await self._plan(goal_handle.request, monitor)
        finally:
            with self._running_lock:
                del self._running[key], self._monitors[key]
                if not self._running:
                    self._feedback_timer.cancel()
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
