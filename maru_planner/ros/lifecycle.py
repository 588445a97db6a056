"""Managed (lifecycle) nodes, as Nav2's servers: configure, activate, deactivate, cleanup, shutdown.

:class:`ManagedNode` is an ``rclpy.lifecycle.LifecycleNode`` whose subclass writes four plain
methods and no transition plumbing:

- ``configure()`` reads the parameters and builds everything (robot, scene, workers, map
  subscription, publishers, services, action servers). Whatever ROS entity it creates is
  remembered and destroyed again by cleanup; its action servers get :meth:`ManagedNode.goal_when_active`
  as their goal callback.
- ``activate()`` / ``deactivate()`` start and stop what is more than answering requests (the
  reactive node's scan subscription and watchdog, a zero ``cmd_vel``); both may be left out.
- ``cleanup()`` releases what ``configure()`` built that is not a ROS entity (worker threads).

While the node is not active its services, created with :meth:`ManagedNode.create_managed_service`,
answer at once with the ``INACTIVE`` code of their response (``PlanningError.INACTIVE``,
``PlanBasePath.INACTIVE``; an empty response where there is no error field), its action servers
reject goals (:meth:`ManagedNode.goal_when_active`) and its lifecycle publishers publish nothing.
Requests admitted before a deactivation finish; cleanup is refused while any is still running.

A transition whose method raises fails (``FAILURE``: the node stays in its state, the reason is
logged on one line). A ``change_state`` request for a transition that does not start from the node's
current state (configure while active, an unknown id or label) is answered ``success: false`` with a
warning, as rclcpp's managed nodes answer it (rclpy alone lets rcl raise, and the process ends).

The read-only parameter ``autostart`` (default true) configures and activates the node at start-up,
as a plain node, raising what ``configure()`` raised so ``main()`` can print one line and exit;
``autostart:=false`` leaves it unconfigured for a lifecycle manager (``ros2 lifecycle set <node>
configure``, ``nav2_lifecycle_manager``). ``destroy_node`` shuts the node down through the shutdown
transition (a deactivation first, when active).
"""

from __future__ import annotations

import inspect
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

import rclpy
from lifecycle_msgs.msg import State, Transition  # type: ignore[import-untyped]
from lifecycle_msgs.srv import ChangeState  # type: ignore[import-untyped]
from rclpy.action import ActionServer, GoalResponse
from rclpy.client import Client
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.lifecycle import Publisher as LifecyclePublisher
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.service import Service
from rclpy.subscription import Subscription
from rclpy.timer import Timer

from maru_planner import heap
from maru_planner.errors import MaruError, excerpt, one_line
from maru_planner.params import ParamSpec
from maru_planner.ros import parameters
from maru_planner.ros.env import network_from_environment
from maru_planner.ros.executor import MultiThreadedExecutor
from maru_planner_interfaces.msg import PlanningError

AUTOSTART = ParamSpec(
    "autostart",
    True,
    "configure and activate at start-up; false = stay unconfigured until a lifecycle manager "
    "(ros2 lifecycle set, nav2_lifecycle_manager) drives the node",
    read_only=True,
)
SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE
NODE_MALLOC_ARENAS = 2  # maru_planner.heap
INACTIVE_WARNING_PERIOD = 5.0  # s between repeats of the "not active" warning
PRIMARY_STATES = frozenset(
    (State.PRIMARY_STATE_UNCONFIGURED, State.PRIMARY_STATE_INACTIVE, State.PRIMARY_STATE_ACTIVE,
     State.PRIMARY_STATE_FINALIZED)
)  # fmt: skip


def inactive_response(response: Any, message: str) -> Any:
    """``response`` refused because the node is not active, in its own error field when it has one."""
    if isinstance(getattr(response, "error", None), PlanningError):
        response.error = PlanningError(code=PlanningError.INACTIVE, message=message, source="lifecycle")
    elif hasattr(response, "error_code") and hasattr(response, "INACTIVE"):
        response.error_code, response.error_msg = response.INACTIVE, message
    return response


class StartupInterrupted(Exception):
    """The ROS context was shut down (Ctrl-C, SIGTERM) while the node configured or activated itself."""


class ManagedNode(LifecycleNode):
    """A lifecycle node whose subclass implements ``configure`` (and optionally the other steps)."""

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self._refuse_invalid_transitions()
        self.autostart: bool = parameters.declare_parameters(self, {AUTOSTART.name: AUTOSTART})[AUTOSTART.name]
        self.is_configured = False
        self.is_active = False
        self.transition_error: Exception | None = None  # what the last failed transition raised
        self._log_failures = True
        self._configured_entities: list[Any] = []
        self._requests = 0
        self._requests_lock = threading.Lock()

    # ------------------------------------------------------------ what a subclass writes
    def configure(self) -> None:
        raise NotImplementedError(f"{type(self).__name__} must implement configure()")

    def activate(self) -> None:
        """Start what is more than answering requests (the default: nothing)."""

    def deactivate(self) -> None:
        """Stop what ``activate`` started, while the publishers still publish (the default: nothing)."""

    def cleanup(self) -> None:
        """Release what ``configure`` built besides ROS entities (the default: nothing)."""

    def requests_in_progress(self) -> int:
        """Service requests still being answered (cleanup waits for none: it is refused while any runs)."""
        with self._requests_lock:
            return self._requests

    def when_configured(self, apply: Callable[[dict[str, Any]], None]) -> Callable[[dict[str, Any]], None]:
        """An on-set ``apply`` that runs only while configured; before, ``configure()`` reads the stored values."""

        def apply_when_configured(changes: dict[str, Any]) -> None:
            if self.is_configured:
                apply(changes)

        return apply_when_configured

    # ------------------------------------------------------------ start-up
    def start(self) -> None:
        """``autostart``: configure and activate now, raising what failed; else wait for a lifecycle manager."""
        if not self.autostart:
            self.get_logger().info(
                f"unconfigured (autostart false): waiting for a lifecycle manager "
                f"(ros2 lifecycle set {self.get_fully_qualified_name()} configure, then activate)"
            )
            return
        self._log_failures = False  # main() reports the one line
        try:
            for trigger in (self.trigger_configure, self.trigger_activate):
                outcome = self._trigger_or_release(trigger)
                if outcome is None:  # a signal (Ctrl-C, SIGTERM) stopped the node meanwhile
                    raise StartupInterrupted
                if outcome != SUCCESS:
                    assert self.transition_error is not None
                    raise self.transition_error
        finally:
            self._log_failures = True

    def _trigger_or_release(self, trigger: Callable[[], Any]) -> Any:
        """``trigger()``'s outcome, or None, with what ``configure`` built released, if a signal shut the context
        down meanwhile: Ctrl-C raises in whatever step runs; after SIGTERM publishing the transition fails."""
        try:
            return trigger()
        except KeyboardInterrupt:
            pass
        except RuntimeError:  # rcl's RCLError
            if self.context.ok():
                raise
        if self.is_configured:
            self._release_without_context()
        return None

    @property
    def state_label(self) -> str:
        if self.is_active:
            return "active"
        return "inactive" if self.is_configured else "unconfigured"

    # ------------------------------------------------------------ serving only while active
    def create_managed_service(self, srv_type: Any, srv_name: str, callback: Callable, **kwargs: Any) -> Service:
        """``create_service`` whose requests are answered only while active (else at once, INACTIVE)."""
        return self.create_service(srv_type, srv_name, self._while_active(srv_name, callback), **kwargs)

    def goal_when_active(self, _goal_request: Any) -> GoalResponse:
        """An action server's ``goal_callback``: goals are accepted only while the node is active."""
        if self.is_active:
            return GoalResponse.ACCEPT
        self._warn_inactive("goal rejected")
        return GoalResponse.REJECT

    def _while_active(self, name: str, callback: Callable) -> Callable:
        if inspect.iscoroutinefunction(callback):

            async def serve_async(request: Any, response: Any) -> Any:
                if not self.is_active:
                    return inactive_response(response, self._warn_inactive(name))
                with self._counted():
                    return await callback(request, response)

            return serve_async

        def serve(request: Any, response: Any) -> Any:
            if not self.is_active:
                return inactive_response(response, self._warn_inactive(name))
            with self._counted():
                return callback(request, response)

        return serve

    @contextmanager
    def _counted(self) -> Iterator[None]:
        with self._requests_lock:
            self._requests += 1
        try:
            yield
        finally:
            with self._requests_lock:
                self._requests -= 1

    def _warn_inactive(self, what: str) -> str:
        message = (
            f"{what}: {self.get_fully_qualified_name()} is {self.state_label}; it serves only while active "
            f"(ros2 lifecycle set {self.get_fully_qualified_name()} activate)"
        )
        self.get_logger().warning(message, throttle_duration_sec=INACTIVE_WARNING_PERIOD)
        return message

    # ------------------------------------------------------------ transitions
    def _refuse_invalid_transitions(self) -> None:
        """Put :meth:`_transition_refusal` in front of rclpy's ``change_state`` service callback.

        rclpy 7 hands a request's transition id to ``rcl_lifecycle_trigger_transition_by_id`` unchecked, and for an
        id that does not start from the current state rcl raises "Transition is not registered" out of the executor:
        the process ends. A label is looked up first and answered ``success: false`` when unknown.
        """
        service = getattr(self, "_service_change_state", None)  # None without the communication interface
        if service is None:
            return
        rclpy_change_state = service.callback

        def change_state(request: ChangeState.Request, response: ChangeState.Response) -> ChangeState.Response:
            refusal = self._transition_refusal(request.transition)
            if refusal is None:
                try:
                    return rclpy_change_state(request, response)
                except RuntimeError as exc:  # rcl's RCLError, should the check above ever miss a case
                    refusal = f"rcl refused it: {one_line(exc)}"
            self.get_logger().warning(f"change_state {self._describe(request.transition)} refused: {refusal}")
            response.success = False
            return response

        service.callback = change_state

    def _transition_refusal(self, transition: Transition) -> str | None:
        """Why ``transition`` cannot start from the current state, or None when it can.

        As in rclcpp, a label, when given, names the transition and the id is ignored (``ros2 service call``
        leaves the id 0). The lifecycle services share the node's mutually exclusive default callback group,
        so the state cannot change between this check and the transition.
        """
        state_id, state = self._state_machine.current_state
        if state_id not in PRIMARY_STATES:
            return f"the node is {state} (a transition is in progress)"
        valid = [(transition_id, label) for transition_id, label, *_ in self._state_machine.available_transitions]
        if transition.label:
            starts_here = any(label == transition.label for _, label in valid)
        else:
            starts_here = any(transition_id == transition.id for transition_id, _ in valid)
        if starts_here:
            return None
        allowed = ", ".join(f"{label} ({transition_id})" for transition_id, label in valid) or "none"
        return f"not allowed while {state} (allowed: {allowed})"

    @staticmethod
    def _describe(transition: Transition) -> str:
        return f"label {excerpt(transition.label)}" if transition.label else f"id {transition.id}"

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        before = self._entities()
        result = self._run("configure", self.configure)
        created = [entity for entity in self._entities() if entity not in before]
        if result != SUCCESS:
            self._destroy(created)
            return result
        for server in created:
            if isinstance(server, ActionServer):
                server.register_goal_callback(self.goal_when_active)
        self._configured_entities = created
        self.is_configured = True
        self.get_logger().info("configured")
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        super().on_activate(state)  # lifecycle publishers on
        result = self._run("activate", self.activate)
        if result != SUCCESS:
            super().on_deactivate(state)
            return result
        self.is_active = True
        self.get_logger().info("active")
        return SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        result = self._run("deactivate", self.deactivate)
        super().on_deactivate(state)  # lifecycle publishers off
        self.get_logger().info("inactive")
        return result

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        running = self.requests_in_progress()
        if running:
            self.transition_error = RuntimeError(f"{running} requests are still being answered; cleanup refused")
            self.get_logger().error(str(self.transition_error))
            return FAILURE
        return self._release()

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """From any primary state: deactivate when active, release when configured (running requests or not)."""
        if self.is_active:
            self.on_deactivate(state)
        if self.is_configured:
            self._release()
        return SUCCESS

    def destroy_node(self) -> None:
        """Shut down through the lifecycle (a reactive node stops its base) before the handles go; after a signal
        shut the context down (no transition can be published) release what ``configure`` built directly."""
        if self.is_configured and self.context.ok():
            self._trigger_or_release(self.trigger_shutdown)
        elif self.is_configured:
            self._release_without_context()
        super().destroy_node()

    def _release_without_context(self) -> None:
        """``cleanup`` (worker processes, temporary files) once the context is gone, quietly: the node is exiting."""
        self.is_active = self.is_configured = False
        try:
            self.cleanup()
        except Exception:  # noqa: BLE001 - exiting, and rosout is gone: nothing left to report it to
            pass

    def _release(self) -> TransitionCallbackReturn:
        result = self._run("cleanup", self.cleanup)
        self._destroy(self._configured_entities)
        self._configured_entities = []
        self.is_configured = False
        self.get_logger().info("unconfigured")
        return result

    def _run(self, transition: str, step: Callable[[], None]) -> TransitionCallbackReturn:
        try:
            step()
        except Exception as exc:  # noqa: BLE001 - a failed transition is reported, the node keeps running
            self.transition_error = exc
            if self._log_failures:
                self.get_logger().error(f"{transition} failed: {one_line(exc)}")
            return FAILURE
        return SUCCESS

    # ------------------------------------------------------------ entities made by configure
    def _entities(self) -> list[Any]:
        return [
            *self.publishers, *self.subscriptions, *self.services, *self.clients, *self.timers,
            *(w for w in self.waitables if isinstance(w, ActionServer)),
        ]  # fmt: skip

    def _destroy(self, entities: list[Any]) -> None:
        for entity in entities:
            if isinstance(entity, ActionServer):
                entity.destroy()
            elif isinstance(entity, LifecyclePublisher):
                self.destroy_lifecycle_publisher(entity)
            elif isinstance(entity, Publisher):
                self.destroy_publisher(entity)
            elif isinstance(entity, Subscription):
                self.destroy_subscription(entity)
            elif isinstance(entity, Service):
                self.destroy_service(entity)
            elif isinstance(entity, Client):
                self.destroy_client(entity)
            elif isinstance(entity, Timer):
                self.destroy_timer(entity)


NodeT = TypeVar("NodeT", bound=Node)


def run_node(
    name: str,
    make_node: Callable[[], NodeT],
    args: list[str] | None = None,
    *,
    startup_errors: tuple[type[BaseException], ...] = (MaruError, ValueError),
    executor_threads: Callable[[NodeT], int] | None = None,
    farewell: Callable[[NodeT], str] | None = None,
) -> int:
    """The whole ``main()`` of a node: networking, init, construction, spin, clean exit.

    Bad start-up input (rcl's own errors, e.g. a params file that is not YAML, and ``startup_errors``
    raised while constructing the node: parameters, robot or scene files) is one stderr line
    ``<name>: cannot start: ...`` and exit code 2, never a traceback; Ctrl-C or SIGTERM while it starts is a quiet
    stop (exit code 0), as while it spins. ``executor_threads`` spins the
    node on a multi-threaded executor of that size; ``farewell`` is logged when the node stops.
    """
    network = network_from_environment()
    heap.limit_arenas(NODE_MALLOC_ARENAS)  # before any thread: each arena keeps its own freed memory
    try:
        rclpy.init(args=args)
    except RuntimeError as exc:  # rcl's RCLError
        print(f"{name}: cannot start: {one_line(exc)}", file=sys.stderr)
        return 2
    try:
        node = make_node()
    except startup_errors as exc:
        print(f"{name}: cannot start: {one_line(exc)}", file=sys.stderr)
        shut_down_context()
        return 2
    except (KeyboardInterrupt, ExternalShutdownException, StartupInterrupted):  # stopped while starting
        shut_down_context()
        return 0
    except RuntimeError:  # rcl's RCLError: a signal shut the context down while the node was being made
        if rclpy.ok():
            raise
        shut_down_context()
        return 0
    node.get_logger().info(network)
    executor = (
        MultiThreadedExecutor(num_threads=executor_threads(node)) if executor_threads else SingleThreadedExecutor()
    )
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:  # rcl's RCLError: a signal shut the context down while the executor was between waits
        if rclpy.ok():
            raise
    finally:
        if farewell is not None:
            node.get_logger().info(farewell(node))
        node.destroy_node()
        shut_down_context()
    return 0


def shut_down_context() -> None:
    """``rclpy.try_shutdown()``, which races with rclpy's signal handler: a signal may shut the context down between
    its check and its own shutdown, which then raises rcl's "rcl_shutdown already called" (CI saw it once, SIGINT
    during configure). Shut down either way is what the caller wants."""
    try:
        rclpy.try_shutdown()
    except RuntimeError:  # rcl's RCLError
        if rclpy.ok():
            raise
