"""Planning as a ROS 2 action: one :class:`~maru_planner.monitor.PlanMonitor` per goal (both planner nodes).

:class:`PlanActionServer` accepts every goal (a managed node, :mod:`maru_planner.ros.lifecycle`,
accepts them only while active), gives it a monitor and runs the node's plan coroutine with it.
While goals run, one timer publishes each running goal's monitor snapshot as feedback (one callback for all
goals, not a timer per goal: a storm of 32 goals costs the executor one wake-up per period); a cancel request
cancels the monitor, which stops the planner at once -- or, for a goal still waiting for a worker, ends it at
once (:meth:`~maru_planner.runtime.PlanningRuntime.plan`). The goal ends SUCCEEDED (the node's
``succeeded(result)``), CANCELED (cancelled and not successful) or ABORTED, always with the result
the plan coroutine returned (the node's service response, as an action result). The server (and
:class:`DrainingActionClient`, for clients) takes every waiting cancel and result request at each executor
wake-up, not one per wake-up as rclpy does: a storm's cancels are answered in one executor round.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections import OrderedDict
from collections.abc import Awaitable, Callable
from typing import Any

from rclpy.action import ActionClient, ActionServer, CancelResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.executors import await_or_execute
from rclpy.node import Node
from rclpy.qos import QoSProfile, qos_profile_services_default

from maru_planner.monitor import PlanMonitor, Progress

CANCEL_SETTLE_TIMEOUT = 1.0  # s a finished goal waits for rclpy to mark its accepted cancel (microseconds in practice)
DRAIN_LIMIT = 256  # cancel or result requests taken per executor wake-up (the services' QoS depth)
# s a finished goal's result is kept for a late get_result (rclpy's default: 900), at most RESULTS_KEPT of them
RESULT_TIMEOUT, RESULTS_KEPT = 60.0, 1024
# s a finished goal stays in rcl (rcl's result timeout), so in every status message. Each status message lists every
# goal rcl keeps, and each client converts all of it to Python (~15 us a goal): at 1 goal/s a 30-min soak's p90
# latencies grew for 15 min, and a storm's 4 clients spent their executor converting status arrays of 260 goals
# (cancel -> result p95 157 ms). Later get_result requests are answered from the server's own copy.
STATUS_RETENTION = 1
# s between two status messages: goals changing state within it go out in one message (a storm of 32 goals made
# ~110 messages, each converted by every client); a change after a quiet period goes out at once
STATUS_PERIOD = 0.02


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
        self._feedback_timer.cancel()  # from the first goal on; idle, it finds no goal to report
        self.server = _DrainingActionServer(
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
            result_timeout=STATUS_RETENTION,
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
            with self._running_lock:  # the timer is never cancelled again: rclpy's executor may be about to call it,
                del self._running[key], self._monitors[key]  # and calling a cancelled timer kills its spin (RCLError)
        if self._succeeded(result):
            goal_handle.succeed()
        elif monitor.cancelled and _cancel_settled(goal_handle):
            goal_handle.canceled()
        else:
            goal_handle.abort()
        return result


class _DrainingActionServer(ActionServer):
    """rclpy's ActionServer taking every waiting cancel and result request at each executor wake-up, not one.

    rclpy takes one request of each kind per wake-up, and every wake-up resumes each goal awaiting its plan:
    16 cancels and 32 result requests of a storm took ~50 wake-ups of 5-25 ms each before the last result left.
    A goal's result goes out from the thread that ends the goal, not from a task of one more executor round.
    rcl forgets a finished goal after :data:`STATUS_RETENTION` (so status messages stay short); its result is
    kept here for :data:`RESULT_TIMEOUT` (at most :data:`RESULTS_KEPT` results) and answers a later request.
    """

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self.status_changed = _Coalesced(self._publish_status, STATUS_PERIOD)
        accepted = self._handle_accepted_callback

        async def coalesced(goal_handle: ServerGoalHandle) -> Any:
            goal_handle.__class__ = _CoalescedStatusGoalHandle  # same object and state; its state changes coalesced
            return await await_or_execute(accepted, goal_handle)

        self.register_handle_accepted_callback(coalesced)
        self._result_requests: dict[bytes, list[Any]] = {}  # goal id -> headers of result requests before its end
        self._result_requests_lock = threading.Lock()
        self._kept_results: OrderedDict[bytes, tuple[float, Any]] = OrderedDict()  # goal id -> (end, response)

    async def _execute_get_result_request(self, request_header_and_message: tuple) -> None:
        header, request = request_header_and_message
        goal = bytes(request.goal_id.uuid)
        future = self._result_futures.get(goal)
        if future is None:  # a goal rcl forgot: its kept result, else rclpy answers STATUS_UNKNOWN
            if (kept := self._kept_result(goal)) is not None:
                self._handle.send_result_response(header, kept)
            else:
                await super()._execute_get_result_request(request_header_and_message)
            return
        with self._result_requests_lock:
            if not future.done():
                self._result_requests.setdefault(goal, []).append(header)
                return
        self._send_result_response(header, future)

    async def _execute_goal(self, execute_callback: Any, goal_handle: ServerGoalHandle) -> None:
        await super()._execute_goal(execute_callback, goal_handle)  # sets the goal's result future
        goal = bytes(goal_handle.goal_id.uuid)
        future = self._result_futures[goal]
        with self._result_requests_lock:
            headers = self._result_requests.pop(goal, [])
            self._keep_result(goal, future.result())
        for header in headers:
            self._send_result_response(header, future)

    def _publish_status(self) -> None:
        try:
            self._handle.publish_status()
        except Exception:  # noqa: BLE001 - destroyed by a lifecycle transition meanwhile: no one to tell
            pass

    def _keep_result(self, goal: bytes, response: Any) -> None:
        """Keep ``response`` for a late request; drop what is older than RESULT_TIMEOUT or beyond RESULTS_KEPT."""
        now = time.monotonic()
        self._kept_results[goal] = (now, response)
        while self._kept_results and (
            len(self._kept_results) > RESULTS_KEPT or next(iter(self._kept_results.values()))[0] < now - RESULT_TIMEOUT
        ):
            self._kept_results.popitem(last=False)

    def _kept_result(self, goal: bytes) -> Any:
        with self._result_requests_lock:
            ended, response = self._kept_results.get(goal, (0.0, None))
        return response if time.monotonic() - ended <= RESULT_TIMEOUT else None

    def take_data(self) -> dict:
        data = super().take_data()
        impl = self._action_type.Impl
        for key, take, request_type in (
            ("cancel", self._handle.take_cancel_request, impl.CancelGoalService.Request),
            ("result", self._handle.take_result_request, impl.GetResultService.Request),
        ):
            if key in data:
                data[key] = [data[key], *_take_waiting(take, request_type, self._lock)]
        return data

    async def execute(self, taken_data: dict) -> None:
        if "goal" in taken_data:
            await self._execute_goal_request(taken_data["goal"])
        for cancel in taken_data.get("cancel", ()):
            await self._execute_cancel_request(cancel)
        for result in taken_data.get("result", ()):
            await self._execute_get_result_request(result)
        if "expired" in taken_data:
            await self._execute_expire_goals(taken_data["expired"])


class _CoalescedStatusGoalHandle(ServerGoalHandle):
    """rclpy's ServerGoalHandle whose state changes ask the server's ``status_changed`` for a status message"""

    def _update_state(self, event: Any) -> None:
        with self._lock:
            if self._goal_handle is None:  # already destroyed
                return
            self._goal_handle.update_goal_state(event)
            self._action_server.status_changed()
            if not self._goal_handle.is_active():
                self._action_server.notify_goal_done()


class _Coalesced:
    """Calls ``action`` at once when it last ran ``period`` ago or more, else once at the end of the period for
    every call made meanwhile (from a timer thread)."""

    def __init__(self, action: Callable[[], None], period: float):
        self._action, self._period = action, period
        self._lock = threading.Lock()
        self._last, self._scheduled = -period, False

    def __call__(self) -> None:
        with self._lock:
            if self._scheduled:
                return
            wait = self._last + self._period - time.monotonic()
            if wait > 0.0:
                self._scheduled = True
            else:
                self._last = time.monotonic()
        if wait > 0.0:
            timer = threading.Timer(wait, self._deferred)
            timer.daemon = True
            timer.start()
        else:
            self._action()

    def _deferred(self) -> None:
        with self._lock:
            self._scheduled, self._last = False, time.monotonic()
        self._action()


class DrainingActionClient(ActionClient):
    """rclpy's ActionClient taking every waiting goal, cancel and result response at each wake-up, not one,
    and without rclpy's lost-response race.

    A client with 8 goals of a storm otherwise needs 8 wake-ups of its executor to see their 8 results.
    rclpy (ros2/rclpy#1123, fixed upstream after our wheels) sends a request before it records the request's
    sequence number: an executor thread that takes the response in between drops it ("Ignoring unexpected
    goal response") and the caller's future never completes. Sending and recording hold one lock, and so does
    matching a response to its request.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._requests_lock = threading.RLock()
        super().__init__(*args, **kwargs)

    def send_goal_async(self, *args: Any, **kwargs: Any) -> Any:
        with self._requests_lock:
            return super().send_goal_async(*args, **kwargs)

    def _cancel_goal_async(self, goal_handle: Any) -> Any:
        with self._requests_lock:
            return super()._cancel_goal_async(goal_handle)

    def _get_result_async(self, goal_handle: Any) -> Any:
        with self._requests_lock:
            return super()._get_result_async(goal_handle)

    def take_data(self) -> dict:
        data = super().take_data()
        impl, handle = self._action_type.Impl, self._client_handle
        for key, take, response_type in (
            ("goal", handle.take_goal_response, impl.SendGoalService.Response),
            ("cancel", handle.take_cancel_response, impl.CancelGoalService.Response),
            ("result", handle.take_result_response, impl.GetResultService.Response),
        ):
            if key in data:
                data[key] = [data[key], *_take_waiting(take, response_type)]
        return data

    async def execute(self, taken_data: dict) -> None:
        for key in ("goal", "cancel", "result"):
            for one in taken_data.pop(key, ()):
                with self._requests_lock:  # rclpy's execute only sets futures for these: it never suspends
                    await super().execute({key: one})
        await super().execute(taken_data)  # feedback and status, one of each as rclpy takes them


def _take_waiting(take: Callable[[Any], tuple], message_type: Any, lock: threading.Lock | None = None) -> list[tuple]:
    """What ``take`` returns until nothing waits ((None, None)), at most :data:`DRAIN_LIMIT` of them."""
    taken: list[tuple] = []
    while len(taken) < DRAIN_LIMIT:
        with lock or contextlib.nullcontext():
            header_and_message = take(message_type)
        if not all(header_and_message):
            break
        taken.append(header_and_message)
    return taken


def _cancel_settled(goal_handle: ServerGoalHandle) -> bool:
    """Whether the goal is CANCELING (only then may it end CANCELED).

    The cancel callback stops the plan before rclpy marks the goal CANCELING, so a plan that stops at
    once may finish first; the mark follows within microseconds on the cancelling executor thread.
    """
    deadline = time.monotonic() + CANCEL_SETTLE_TIMEOUT
    while not goal_handle.is_cancel_requested and time.monotonic() < deadline:
        time.sleep(0.0005)
    return goal_handle.is_cancel_requested
