"""A small synchronous client for ``planning_node`` (demo, benchmarks, scripts).

>>> from maru_planner.ros.planning_client import PlanningClient
>>> with PlanningClient() as client:            # own node, spun in a background thread
...     response = client.plan(goal_joints={"waist_yaw": 0.9, ...}, start={...}, planner_id="RRTConnect")
...     response.error.code == PlanningError.SUCCESS, response.trajectory

Call ``rclpy.init()`` first (or pass ``init=True``, which keeps the user's DDS networking, as the
nodes do: ``maru_planner.ros.env.network_from_environment``). Every method returns the service response as is; a
call that gets no answer within ``timeout`` raises ``TimeoutError``.

Nothing lost in a burst: with Fast DDS every client of a service receives the replies to *all* clients on
the service's one reply topic and keeps only the newest ``depth`` of them, so with rclpy's default (10) a
client's own answer is evicted when more than 10 calls are answered at once (issue 36: 27 of 320 lost).
The clients here use :data:`REPLY_QOS` (depth 256, the node's ``request_queue_depth``) for every service
and the action's goal, result and cancel services; pass ``qos=`` for a deeper one. :meth:`PlanningClient.plan_async`
returns the request id (the client's sequence number) with the pending answer.

The ``plan_motion`` action, watched and cancellable::

    goal = client.plan_action(goal_joints, start=start, planner_id="RRT", feedback_callback=print)
    goal.cancel()                      # the node stops the search within milliseconds
    status, result = goal.result()     # GoalStatus.STATUS_CANCELED, the statistics so far
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import rclpy
from action_msgs.msg import GoalStatus
from geometry_msgs.msg import Pose, PoseStamped
from lifecycle_msgs.msg import Transition  # type: ignore[import-untyped]
from lifecycle_msgs.srv import ChangeState, GetState  # type: ignore[import-untyped]
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from sensor_msgs.msg import JointState

from maru_planner.ros import planning_conversions as conv
from maru_planner.ros.env import network_from_environment
from maru_planner.ros.plan_actions import DrainingActionClient
from maru_planner_interfaces.action import PlanMotion as PlanMotionAction
from maru_planner_interfaces.msg import SceneObstacle
from maru_planner_interfaces.srv import (
    ApplyScene,
    CheckStateValidity,
    ComputeCartesianPath,
    ComputeFK,
    ComputeIK,
    GetScene,
    PlanMotion,
    QueryPlanners,
)

AnswerT = TypeVar("AnswerT")

REPLY_DEPTH = 256  # >= the calls answered at once across every client of a service (module doc)
REPLY_QOS = QoSProfile(
    depth=REPLY_DEPTH,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
FEEDBACK_QOS = QoSProfile(depth=100)  # every goal's feedback shares one topic; a lost one is only a late update


class PlanningClient:
    """Clients of ``plan_motion`` (service and action), ``compute_ik``, ``apply_scene`` and ``get_scene``.

    ``node``: an existing node that someone else spins (an executor thread); if None the
    client makes its own node and spins it in a daemon thread. ``namespace``: where the
    planning node's services live (``""`` = the root namespace). ``qos``: of every service client and
    the action's services (its depth >= the calls answered at once by the node, module doc). ``server_name``:
    the node's name, for its lifecycle and parameter services (:meth:`change_state`, :meth:`set_parameters`).
    """

    def __init__(
        self,
        node=None,
        namespace: str = "",
        *,
        node_name: str = "planning_client",
        init: bool = False,
        qos: QoSProfile = REPLY_QOS,
        server_name: str = "planning_node",
    ):
        if init and not rclpy.ok():
            network_from_environment()
            rclpy.init()
        self._owns_node = node is None
        self.node = node if node is not None else rclpy.create_node(node_name)
        prefix = namespace.rstrip("/") + "/" if namespace else ""
        self.plan_client = self.node.create_client(PlanMotion, prefix + "plan_motion", qos_profile=qos)
        self.ik_client = self.node.create_client(ComputeIK, prefix + "compute_ik", qos_profile=qos)
        self.apply_client = self.node.create_client(ApplyScene, prefix + "apply_scene", qos_profile=qos)
        self.scene_client = self.node.create_client(GetScene, prefix + "get_scene", qos_profile=qos)
        self.fk_client = self.node.create_client(ComputeFK, prefix + "compute_fk", qos_profile=qos)
        self.validity_client = self.node.create_client(
            CheckStateValidity, prefix + "check_state_validity", qos_profile=qos
        )
        self.planners_client = self.node.create_client(QueryPlanners, prefix + "query_planners", qos_profile=qos)
        self.cartesian_client = self.node.create_client(
            ComputeCartesianPath, prefix + "compute_cartesian_path", qos_profile=qos
        )
        self.plan_action_client = plan_action_client(self.node, prefix + "plan_motion", qos)
        self._server = prefix + server_name  # the node's own services: lifecycle, parameters
        self._qos = qos
        self._node_clients: dict[str, Any] = {}  # made on first use
        self._executor = None
        if self._owns_node:
            self._executor = SingleThreadedExecutor()
            self._executor.add_node(self.node)
            self._thread = threading.Thread(target=self._executor.spin, daemon=True)
            self._thread.start()

    # ------------------------------------------------------------ calls

    def wait_until_ready(self, timeout: float = 60.0) -> None:
        """Wait until every service and the ``plan_motion`` action of the node answer (see :func:`call_until_answered`).

        The probes change nothing: an empty plan / IK request and an empty goal (answered
        INVALID_REQUEST), removing an obstacle name no scene uses (INVALID_SCENE), reading the scene.
        """
        deadline = time.monotonic() + timeout
        probes = (
            (self.scene_client, GetScene.Request()),
            (self.plan_client, PlanMotion.Request()),
            (self.ik_client, ComputeIK.Request()),
            (self.apply_client, ApplyScene.Request(obstacles=[_removal(" no such obstacle ")])),
        )
        for client, request in probes:
            call_until_answered(client, request, max(deadline - time.monotonic(), 0.001))
        goal_until_answered(self.plan_action_client, PlanMotionAction.Goal(), max(deadline - time.monotonic(), 0.001))

    def call(self, client, request, timeout: float = 60.0):
        """Send ``request`` and wait for the response (the node must be spun by an executor)."""
        return call_service(client, request, timeout)

    def plan(
        self, goal_joints: dict[str, float] | None = None, *, timeout: float | None = None, **request_fields
    ) -> PlanMotion.Response:
        """Plan to ``goal_joints`` ({joint: rad}) or ``goal_poses`` ({link: 4x4 or Pose}).

        ``request_fields`` are :func:`plan_request`'s keywords (``start`` None = the node uses the
        latest /joint_states, ``group``, ``planner_id``, ``time_budget`` (default 5 s), ``seed``, ...).
        ``timeout`` defaults to the time budget + 30 s. Returns the response;
        check ``response.error.code == PlanningError.SUCCESS``.
        """
        request = plan_request(goal_joints, **request_fields)
        return self.call(self.plan_client, request, timeout or request.allowed_planning_time + 30.0)

    def plan_async(self, goal_joints: dict[str, float] | None = None, **request_fields) -> PendingCall:
        """Send a plan request (:meth:`plan`'s fields) without waiting: its request id and pending answer."""
        return send_request(self.plan_client, plan_request(goal_joints, **request_fields))

    def plan_action(
        self,
        goal_joints: dict[str, float] | None = None,
        *,
        feedback_callback: Callable[[PlanMotionAction.Feedback], None] | None = None,
        timeout: float = 60.0,
        **request_fields,
    ) -> PlanGoal:
        """Send a ``plan_motion`` action goal (``request_fields`` as for :meth:`plan`) and wait until it is accepted.

        ``feedback_callback`` gets every feedback message (stage, elapsed, nodes, best_cost, tracking_error) in
        the client's executor thread; ``execute=True`` also executes the plan (stage ``executing``). Returns the
        running :class:`PlanGoal` (``cancel()``, ``result()``).
        """
        return send_plan_goal(
            self.plan_action_client, plan_goal(goal_joints, **request_fields), feedback_callback, timeout
        )

    def compute_ik(
        self,
        goal_poses: dict,
        *,
        group: str = "",
        seed: dict[str, float] | None = None,
        avoid_collisions: bool = True,
        ik_timeout: float = 0.0,
        frame_id: str = "base_link",
        timeout: float = 30.0,
    ) -> ComputeIK.Response:
        """Joint state reaching ``goal_poses`` ({link: 4x4 or Pose}); ``seed`` None = latest /joint_states."""
        request = ComputeIK.Request(group=group, timeout=float(ik_timeout), avoid_collisions=avoid_collisions)
        request.links, request.poses = _stamped_poses(goal_poses, frame_id)
        if seed:
            request.seed_state = _joint_state(seed)
        return self.call(self.ik_client, request, timeout)

    def apply_scene(self, obstacles: Sequence[SceneObstacle] = (), *, clear: bool = False, timeout: float = 30.0):
        """Add/move/remove ``SceneObstacle`` messages (after an optional clear)."""
        return self.call(self.apply_client, ApplyScene.Request(clear=clear, obstacles=list(obstacles)), timeout)

    def add_obstacle(self, name: str, shape: str, dimensions, pose, frame_id: str = "base_link", **kwargs):
        """Add (or replace) a shape of the table at ``pose`` (4x4), its ``SolidPrimitive`` dimensions as listed

        (box [x, y, z], sphere [r], cylinder [height, r]).
        """
        return self.apply_scene([obstacle_msg(name, shape, dimensions, pose, frame_id)], **kwargs)

    def remove_obstacle(self, name: str, **kwargs):
        return self.apply_scene([_removal(name)], **kwargs)

    def get_scene(self, timeout: float = 30.0) -> GetScene.Response:
        return self.call(self.scene_client, GetScene.Request(), timeout)

    def attach(
        self, name: str, link: str, *, touch_links: Sequence[str] = (), shape: str = "", dimensions=(), pose=None,
        robot_state: dict[str, float] | None = None, frame_id: str = "base_link", **kwargs,
    ) -> ApplyScene.Response:  # fmt: skip
        """Attach scene obstacle ``name`` to ``link`` where it is, or (``shape`` given) a new shape at ``pose``
        (4x4 in ``frame_id``); ``robot_state`` places the link (None: the node's latest /joint_states)."""
        msg = obstacle_msg(name, shape, dimensions, pose, frame_id) if shape else SceneObstacle(name=name)
        msg.operation, msg.link_name, msg.touch_links = SceneObstacle.ATTACH, link, list(touch_links)
        msg.header.frame_id = frame_id
        if robot_state:
            msg.robot_state = _joint_state(robot_state)
        return self.apply_scene([msg], **kwargs)

    def detach(self, name: str, *, robot_state: dict[str, float] | None = None, **kwargs) -> ApplyScene.Response:
        """Put attached object ``name`` back into the scene where ``robot_state`` (None: the latest) holds it."""
        msg = SceneObstacle(name=name, operation=SceneObstacle.DETACH)
        if robot_state:
            msg.robot_state = _joint_state(robot_state)
        return self.apply_scene([msg], **kwargs)

    def compute_fk(
        self, robot_state: dict[str, float] | None = None, links: Sequence[str] = (), timeout: float = 30.0
    ) -> ComputeFK.Response:
        """Poses of ``links`` (empty: every link) at ``robot_state`` (None: the node's latest /joint_states)."""
        request = ComputeFK.Request(links=list(links))
        if robot_state:
            request.robot_state = _joint_state(robot_state)
        return self.call(self.fk_client, request, timeout)

    def check_state_validity(
        self, robot_state: dict[str, float] | None = None, constraints=None, timeout: float = 30.0
    ) -> CheckStateValidity.Response:
        """Validity, colliding pairs, clearance (and ``PathConstraints`` message violations) at ``robot_state``."""
        request = CheckStateValidity.Request()
        if robot_state:
            request.robot_state = _joint_state(robot_state)
        if constraints is not None:
            request.constraints = constraints
        return self.call(self.validity_client, request, timeout)

    def query_planners(self, timeout: float = 30.0) -> QueryPlanners.Response:
        return self.call(self.planners_client, QueryPlanners.Request(), timeout)

    def cartesian_path(
        self, waypoints: list, *, start: dict[str, float] | None = None, group: str = "", link: str = "",
        max_step: float = 0.0, jump_threshold: float = 0.0, avoid_collisions: bool = True,
        velocity_scaling: float = 0.0, acceleration_scaling: float = 0.0, timeout: float = 60.0,
    ) -> ComputeCartesianPath.Response:  # fmt: skip
        """Straight-line path of ``link`` through ``waypoints`` (4x4 poses or ``Pose`` s in the planning frame)."""
        request = ComputeCartesianPath.Request(
            group=group, link=link, max_step=float(max_step), jump_threshold=float(jump_threshold),
            avoid_collisions=avoid_collisions, max_velocity_scaling_factor=float(velocity_scaling),
            max_acceleration_scaling_factor=float(acceleration_scaling),
        )  # fmt: skip
        request.waypoints = [_pose(w) for w in waypoints]
        if start:
            request.start_state = _joint_state(start)
        return self.call(self.cartesian_client, request, timeout)

    # ------------------------------------------------------------ the node's lifecycle and parameters

    def get_state(self, timeout: float = 30.0) -> str:
        """The node's lifecycle state: "unconfigured", "inactive", "active", "finalized" (``ros2 lifecycle get``)."""
        return self.call(self._node_client(GetState, "get_state"), GetState.Request(), timeout).current_state.label

    def change_state(self, transition: str, timeout: float = 60.0) -> bool:
        """Trigger ``transition`` ("configure", "activate", "deactivate", "cleanup", "shutdown"; ``ros2 lifecycle
        set``); whether the node made it. ValueError for another name."""
        ids = {"configure": Transition.TRANSITION_CONFIGURE, "activate": Transition.TRANSITION_ACTIVATE,
               "deactivate": Transition.TRANSITION_DEACTIVATE, "cleanup": Transition.TRANSITION_CLEANUP,
               "shutdown": Transition.TRANSITION_INACTIVE_SHUTDOWN}  # fmt: skip
        if transition not in ids:
            raise ValueError(f"unknown transition {transition!r} (have {', '.join(ids)})")
        request = ChangeState.Request(transition=Transition(id=ids[transition]))
        return bool(self.call(self._node_client(ChangeState, "change_state"), request, timeout).success)

    def get_parameters(self, *names: str, timeout: float = 30.0) -> dict[str, Any]:
        """{name: value} of the node's parameters (``ros2 param get``); KeyError naming those the node lacks."""
        client = self._node_client(GetParameters, "get_parameters")
        values = self.call(client, GetParameters.Request(names=list(names)), timeout).values
        if len(values) != len(names):  # rclpy answers nothing when one name is unknown: find which
            lacking = [n for n in names if not self.call(client, GetParameters.Request(names=[n]), timeout).values]
            raise KeyError(f"{self._server} has no parameter {', '.join(map(repr, lacking))}")
        return {name: parameter_value_to_python(value) for name, value in zip(names, values)}

    def set_parameters(self, timeout: float = 30.0, **values: Any) -> dict[str, str]:
        """Set the node's parameters (``ros2 param set``); {name: reason} of those it rejected (empty: all set)."""
        request = SetParameters.Request(
            parameters=[Parameter(n, value=v).to_parameter_msg() for n, v in values.items()]
        )
        response = self.call(self._node_client(SetParameters, "set_parameters"), request, timeout)
        return {name: r.reason for name, r in zip(values, response.results) if not r.successful}

    def _node_client(self, srv_type: Any, service: str) -> Any:
        if service not in self._node_clients:
            name = f"{self._server}/{service}"
            self._node_clients[service] = self.node.create_client(srv_type, name, qos_profile=self._qos)
        return self._node_clients[service]

    # ------------------------------------------------------------ lifetime

    def close(self) -> None:
        if self._executor is not None:  # the client spins its own node
            self._executor.shutdown(timeout_sec=10.0)
            self._thread.join(timeout=10.0)  # out of the wait set before the node's handles go
            self.node.destroy_node()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class PlanGoal:
    """An accepted ``plan_motion`` action goal: its result request is already on its way."""

    def __init__(self, handle: ClientGoalHandle):
        self.handle = handle
        self._result = handle.get_result_async()

    @property
    def done(self) -> bool:
        return self._result.done()

    def cancel(self, timeout: float = 30.0) -> bool:
        """Ask the node to cancel the goal; whether it accepted (False once the goal has ended)."""
        response = wait_for_future(self.handle.cancel_goal_async(), timeout, "plan_motion cancel")
        return len(response.goals_canceling) > 0

    def result(self, timeout: float = 120.0) -> tuple[int, PlanMotionAction.Result]:
        """(``action_msgs/GoalStatus`` status, result) once the goal has ended: SUCCEEDED, ABORTED or CANCELED."""
        response = wait_for_future(self._result, timeout, "plan_motion result")
        return response.status, response.result


def plan_action_client(node, name: str = "plan_motion", qos: QoSProfile = REPLY_QOS) -> ActionClient:
    """A ``plan_motion`` action client whose goal, result and cancel answers are never evicted (module doc)."""
    return DrainingActionClient(
        node, PlanMotionAction, name, goal_service_qos_profile=qos, result_service_qos_profile=qos,
        cancel_service_qos_profile=qos, feedback_sub_qos_profile=FEEDBACK_QOS,
    )  # fmt: skip


class PendingCall:
    """A service request sent: its ``request_id`` (the client's sequence number, as the middleware numbers it)
    and the answer to come (``result(timeout)``)."""

    def __init__(self, client, request_id: int, future: Future):
        self.client, self.request_id, self.future = client, request_id, future

    def result(self, timeout: float = 60.0):
        """The response; TimeoutError (the request forgotten by the client) if none within ``timeout``."""
        try:
            return wait_for_future(self.future, timeout, f"response from {self.client.srv_name}")
        except TimeoutError:
            self.client.remove_pending_request(self.future)
            raise


def send_request(client, request) -> PendingCall:
    """What ``client.call_async(request)`` does (rclpy Jazzy), keeping the request's sequence number, which
    call_async does not return (read back later, the answer may have removed it)."""
    if not isinstance(request, client.srv_type.Request):
        raise TypeError(f"{client.srv_name} takes {client.srv_type.Request.__name__}, got {type(request).__name__}")
    with client._lock:  # the executor looks the answer's sequence number up under it
        with client.handle:
            request_id = client.handle.send_request(request)
        future = Future()
        client._pending_requests[request_id] = future
        future.add_done_callback(client.remove_pending_request)
    return PendingCall(client, request_id, future)


def plan_goal(
    goal_joints: dict[str, float] | None = None, *, execute: bool = False, **request_fields
) -> PlanMotionAction.Goal:
    """A ``PlanMotion`` action goal from plain Python values (:func:`plan_request`'s keywords); ``execute``: the
    node sends the certified trajectory to its ``execution_action`` (docs/real_robot.md)."""
    request = plan_request(goal_joints, **request_fields)
    fields = {name: getattr(request, name) for name in PlanMotion.Request.get_fields_and_field_types()}
    return PlanMotionAction.Goal(execute=execute, **fields)


def send_plan_goal(
    client: ActionClient,
    goal: PlanMotionAction.Goal,
    feedback_callback: Callable[[PlanMotionAction.Feedback], None] | None = None,
    timeout: float = 60.0,
) -> PlanGoal:
    """Send ``goal`` on a planning action client and wait for its acceptance (an active node never rejects)."""
    if not client.wait_for_server(timeout_sec=timeout):
        raise TimeoutError(f"no plan_motion action server after {timeout} s")
    on_feedback = None if feedback_callback is None else (lambda message: feedback_callback(message.feedback))
    handle = wait_for_future(client.send_goal_async(goal, feedback_callback=on_feedback), timeout, "plan_motion goal")
    if not handle.accepted:
        raise RuntimeError("plan_motion rejected the goal")
    return PlanGoal(handle)


def goal_until_answered(client: ActionClient, goal: Any, timeout: float = 60.0) -> tuple[int, Any]:
    """Send a harmless ``goal`` again and again until its result arrives; (status, result).

    As for services (:func:`call_until_answered`): right after discovery the server may not yet have
    matched the client's readers, and the goal's acceptance or result is lost. Only for goals that
    change nothing.
    """
    return _until_answered(
        lambda wait: send_plan_goal(client, goal, timeout=wait).result(wait),
        timeout,
        f"no answer to a probe goal within {timeout} s",
    )


def wait_for_future(future: Future, timeout: float, what: str):
    """The result of an rclpy future that an executor thread completes (blocks without polling)."""
    answered = threading.Event()
    future.add_done_callback(lambda _future: answered.set())
    if not answered.wait(timeout):
        raise TimeoutError(f"no {what} within {timeout} s")
    return future.result()


def status_name(status: int) -> str:
    """``action_msgs/GoalStatus`` constant name of ``status`` (e.g. "STATUS_CANCELED")."""
    names = {getattr(GoalStatus, n): n for n in dir(GoalStatus) if n.startswith("STATUS_")}
    return names.get(status, f"UNKNOWN({status})")


def call_service(client, request, timeout: float = 60.0):
    """Call ``client`` and wait for the answer; its node must be spun by an executor thread."""
    if not client.wait_for_service(timeout_sec=timeout):
        raise TimeoutError(f"service {client.srv_name} not available after {timeout} s")
    return send_request(client, request).result(timeout)


def call_until_answered(client, request, timeout: float = 60.0):
    """Send a harmless ``request`` again and again until one is answered; return that answer.

    ``wait_for_service`` only says that this client has matched the server. Right after
    discovery the server may not have matched the client's response reader yet, and
    rmw_fastrtps then drops the answer (the client would wait for nothing). An answer
    that comes back proves both directions, so later calls are safe. Only for requests
    that change nothing (they may be served more than once).
    """
    failure = f"{client.srv_name} never answered within {timeout} s"
    return _until_answered(lambda wait: call_service(client, request, wait), timeout, failure)


def _until_answered(send: Callable[[float], AnswerT], timeout: float, failure: str) -> AnswerT:
    """``send(wait)`` again and again, each try waiting longer, until one returns; after ``timeout``: TimeoutError."""
    deadline = time.monotonic() + timeout
    attempt = 1.0
    while True:
        left = deadline - time.monotonic()
        if left <= 0.0:
            raise TimeoutError(failure)
        try:
            return send(min(attempt, left))
        except TimeoutError:
            attempt = min(2.0 * attempt, 8.0)  # a slow server gets more time on each try


def plan_request(
    goal_joints: dict[str, float] | None = None,
    *,
    goal_poses: dict | None = None,
    start: dict[str, float] | None = None,
    group: str = "",
    planner_id: str = "",
    time_budget: float = 5.0,
    seed: int = -1,
    attempts: int = 1,
    velocity_scaling: float = 1.0,
    acceleration_scaling: float = 1.0,
    frame_id: str = "base_link",
) -> PlanMotion.Request:
    """A ``PlanMotion.Request`` from plain Python values."""
    request = PlanMotion.Request(
        group=group,
        planner_id=planner_id,
        allowed_planning_time=float(time_budget),
        num_attempts=int(attempts),
        seed=int(seed),
        max_velocity_scaling_factor=float(velocity_scaling),
        max_acceleration_scaling_factor=float(acceleration_scaling),
    )
    if start:
        request.start_state = _joint_state(start)
    if goal_joints:
        request.goal_joint_names = list(goal_joints)
        request.goal_positions = [float(v) for v in goal_joints.values()]
    if goal_poses:
        request.goal_links, request.goal_poses = _stamped_poses(goal_poses, frame_id)
    return request


def obstacle_msg(name: str, shape: str, dimensions, pose, frame_id: str = "base_link") -> SceneObstacle:
    """``SceneObstacle`` ADD of a primitive shape (``pose`` a 4x4 matrix or a ``geometry_msgs/Pose``)."""
    msg = SceneObstacle(name=name, operation=SceneObstacle.ADD)
    msg.header.frame_id = frame_id
    msg.shape = conv.primitive_msg(shape, dimensions, f"obstacle '{name}'")
    msg.pose = _pose(pose)
    return msg


def _removal(name: str) -> SceneObstacle:
    return SceneObstacle(name=name, operation=SceneObstacle.REMOVE)


def _joint_state(values: dict[str, float]) -> JointState:
    return conv.joint_state_msg(list(values), list(values.values()))


def _pose(pose):
    return pose if isinstance(pose, Pose) else conv.matrix_to_pose(pose)


def _stamped_poses(poses: dict, frame_id: str):
    links, stamped = [], []
    for link, pose in poses.items():
        msg = PoseStamped(pose=_pose(pose))
        msg.header.frame_id = frame_id
        links.append(link)
        stamped.append(msg)
    return links, stamped
