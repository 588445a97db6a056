"""Plan, then execute: a ``plan_motion`` goal with ``execute`` sends its certified trajectory to a
FollowJointTrajectory-compatible action server (MoveIt's MoveGroup ``plan_and_execute``).

:class:`TrajectoryExecution` holds the node's action client (``execution_action`` of type
``execution_action_type``: arm_sim_node's ``ExecuteTrajectory`` or control_msgs' ``FollowJointTrajectory``, whose
goal, feedback and result share the fields used here). :meth:`TrajectoryExecution.execute` runs in the plan
goal's coroutine: it waits ``execution_server_timeout`` for the server, sends the trajectory to start now
(header stamp zero), passes the server's feedback on through the goal's :class:`~maru_planner.monitor.PlanMonitor`
as stage ``executing`` (with the tracking error), cancels the execution when the plan goal is cancelled
(the monitor's terminate hook) or when no result comes within duration x ``execution_duration_scaling`` +
``execution_duration_margin``, and writes the outcome into the plan goal's result (``execution_*`` fields).
"""

from __future__ import annotations

import copy
import importlib
import math
import threading
import time
from typing import Any

from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Time
from rclpy.action import ActionClient
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from rclpy.task import Future
from trajectory_msgs.msg import JointTrajectory

from maru_planner import errors
from maru_planner.errors import one_line
from maru_planner.monitor import PlanMonitor, Progress
from maru_planner.ros import planning_requests as requests
from maru_planner.ros.plan_actions import DrainingActionClient
from maru_planner.ros.planning_parameters import NodeSettings
from maru_planner_interfaces.action import PlanMotion as PlanMotionAction

R = PlanMotionAction.Result
SUCCESSFUL = 0  # control_msgs/FollowJointTrajectory's (and ExecuteTrajectory's) SUCCESSFUL
CANCEL_WAIT = 5.0  # s a cancelled execution is given to come to rest and answer
POLL = 0.02  # s between looks for the server


def action_type(name: str) -> Any:
    """The action class of ``package/action/Name``; InvalidParameter (one line) when it cannot be imported."""
    package, kind, type_name = (name.split("/") + ["", ""])[:3]
    try:
        module = importlib.import_module(f"{package}.{kind}")
        return getattr(module, type_name)
    except (ImportError, AttributeError, ValueError):
        raise errors.InvalidParameter(
            f"parameter 'execution_action_type': cannot import {name!r} (is its package installed?)"
        ) from None


def feedback_msg(progress: Progress) -> PlanMotionAction.Feedback:
    """The plan goal's feedback: the planner's progress, and while executing the latest tracking error."""
    msg = requests.feedback_msg(progress)
    msg.tracking_error = float(progress.info.get("tracking_error", math.nan))
    return msg


def mark_not_run(result: Any, reason: str, code: int = R.EXECUTION_NOT_RUN) -> None:
    """Fill a plan goal's execution fields for a trajectory that was not executed (services have none)."""
    if hasattr(result, "execution_error_code"):
        result.execution_error_code = code
        result.execution_error_string = reason
        result.execution_tracking_error = math.nan
        result.execution_time = 0.0


class _Canceller:
    """A :meth:`PlanMonitor.attach` hook: cancelling the plan goal cancels the running execution goal."""

    def __init__(self, handle: Any):
        self.handle = handle
        self.requested = False

    def terminate(self) -> None:
        self.requested = True
        self.handle.cancel_goal_async()


class TrajectoryExecution:
    """The node's execution action client and the coroutine that executes one plan (module doc)."""

    def __init__(self, node: Node, settings: NodeSettings, callback_group: CallbackGroup):
        self._node = node
        self._callback_group = callback_group
        self._retired: list[ActionClient] = []  # clients of earlier targets: a goal may still be executing on one
        self._type = action_type(settings.execution_action_type)
        self.action_name = settings.execution_action
        self.client = DrainingActionClient(node, self._type, self.action_name, callback_group=callback_group)

    def retarget(self, settings: NodeSettings) -> None:
        """Send the next goals to ``settings``' execution action (InvalidParameter for a bad name)."""
        kind = action_type(settings.execution_action_type)
        try:
            client = DrainingActionClient(
                self._node, kind, settings.execution_action, callback_group=self._callback_group
            )
        except ValueError as exc:  # rclpy's: a bad name, with rcl's source location
            raise errors.InvalidParameter(f"parameter 'execution_action': {str(exc).split(', at ')[0]}") from None
        self._retired.append(self.client)
        self._type, self.action_name, self.client = kind, settings.execution_action, client

    def destroy(self) -> None:
        for client in (*self._retired, self.client):
            client.destroy()
        self._retired.clear()

    async def execute(
        self, trajectory: JointTrajectory, result: Any, monitor: PlanMonitor | None, settings: NodeSettings
    ) -> None:
        """Execute ``trajectory`` and fill ``result``'s ``execution_*`` fields (never raises)."""
        started = time.monotonic()
        monitor = monitor or PlanMonitor()
        tracking = _Tracking(monitor)
        try:
            code, message = await self._run(trajectory, monitor, tracking, settings)
        except errors.PlanningCancelled:
            code, message = R.EXECUTION_CANCELED, "plan goal cancelled before execution started"
        except Exception as exc:  # noqa: BLE001 - any failure is an outcome of the goal, not a dead node
            code, message = R.EXECUTION_REJECTED, f"{type(exc).__name__}: {exc}"
        result.execution_error_code = int(code)
        result.execution_error_string = one_line(message)
        result.execution_tracking_error = tracking.max_error
        result.execution_time = time.monotonic() - started
        outcome = (
            f"execution on {self.action_name}: {code} {result.execution_error_string} "
            f"(tracking error {tracking.max_error:.4f} rad, {result.execution_time:.2f} s)"
        )
        if code == SUCCESSFUL:  # rclpy fixes a call site's severity: one call per level
            self._node.get_logger().info(outcome)
        else:
            self._node.get_logger().warning(outcome)

    async def _run(
        self, trajectory: JointTrajectory, monitor: PlanMonitor, tracking: _Tracking, settings: NodeSettings
    ) -> tuple[int, str]:
        monitor.report("executing")  # raises PlanningCancelled when the goal was cancelled meanwhile
        client, kind = self.client, self._type  # this goal's, whatever a parameter change does meanwhile
        if not await self._server_ready(client, settings.execution_server_timeout):
            return R.EXECUTION_SERVER_UNAVAILABLE, (
                f"no action server '{self.action_name}' ({settings.execution_action_type}) within "
                f"{settings.execution_server_timeout} s (parameter execution_action)"
            )
        goal = kind.Goal()
        goal.trajectory = copy.deepcopy(trajectory)
        goal.trajectory.header.stamp = Time()  # start now, as joint_trajectory_controller reads a zero stamp
        handle = await client.send_goal_async(goal, feedback_callback=tracking)
        if handle is None or not handle.accepted:
            return R.EXECUTION_REJECTED, f"'{self.action_name}' rejected the trajectory"
        canceller = _Canceller(handle)
        duration = _duration(trajectory)
        budget = duration * settings.execution_duration_scaling + settings.execution_duration_margin
        with monitor.attach(canceller):
            response = await self._within(handle.get_result_async(), budget)
            if response is None:  # overran: cancel, give the arm time to stop
                handle.cancel_goal_async()
                response = await self._within(handle.get_result_async(), CANCEL_WAIT)
                if response is None:
                    return R.EXECUTION_NO_RESULT, f"no result from '{self.action_name}' within {budget:.2f} s"
                return R.EXECUTION_NO_RESULT, (
                    f"no result within {budget:.2f} s ({duration:.2f} s x {settings.execution_duration_scaling} + "
                    f"{settings.execution_duration_margin} s): cancelled"
                )
        answer = response.result
        tracking.add(float(getattr(answer, "max_tracking_error", 0.0)))
        if response.status == GoalStatus.STATUS_CANCELED or canceller.requested:
            return R.EXECUTION_CANCELED, f"cancelled with the plan goal ({answer.error_string})"
        return int(answer.error_code), str(answer.error_string) or "goal reached"

    async def _server_ready(self, client: ActionClient, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while not client.server_is_ready():
            if time.monotonic() >= deadline:
                return False
            await self._sleep(POLL)
        return True

    def _sleep(self, seconds: float) -> Future:
        """A future done after ``seconds`` (a coroutine awaits it without holding an executor thread)."""
        done = Future(executor=self._node.executor)
        timer = threading.Timer(seconds, lambda: self._resolve(done, None))
        timer.daemon = True
        timer.start()
        return done

    def _within(self, future: Future, seconds: float) -> Future:
        """A future with ``future``'s result, or None after ``seconds`` when it has none by then."""
        first = Future(executor=self._node.executor)
        lock = threading.Lock()

        def settle(value: Any) -> None:
            with lock:
                if not first.done():
                    self._resolve(first, value)

        timer = threading.Timer(seconds, settle, args=(None,))
        timer.daemon = True
        timer.start()

        def answered(done: Future) -> None:
            timer.cancel()
            settle(done.result())

        future.add_done_callback(answered)
        return first

    def _resolve(self, future: Future, value: Any) -> None:
        future.set_result(value)
        if self._node.executor is not None:
            self._node.executor.wake()


class _Tracking:
    """The action server's feedback as the plan goal's: stage ``executing``, the largest tracking error so far."""

    def __init__(self, monitor: PlanMonitor):
        self._monitor = monitor
        self.max_error = math.nan

    def add(self, error: float) -> None:
        if math.isfinite(error):
            self.max_error = error if math.isnan(self.max_error) else max(self.max_error, error)

    def __call__(self, message: Any) -> None:
        errors_now = [abs(e) for e in message.feedback.error.positions]
        now = max(errors_now, default=math.nan)
        self.add(now)
        self._monitor.stage = "executing"
        self._monitor.info["tracking_error"] = now


def _duration(trajectory: JointTrajectory) -> float:
    if not trajectory.points:
        return 0.0
    last = trajectory.points[-1].time_from_start
    return last.sec + 1e-9 * last.nanosec
