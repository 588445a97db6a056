"""``planning_node``: ROS 2 services around the planning runtime (:mod:`maru_planner.runtime`).

A thin adapter: messages are converted in :mod:`planning_conversions` and :mod:`planning_requests`; the work is
done by a :class:`~maru_planner.runtime.PlanningRuntime` (robot, versioned scene, admission -- BUSY when a
request's expected wait exceeds its budget or ``workers + queue_size`` wait --, worker threads and processes,
warm-up, IK), built at configure, shut down at cleanup.
Service callbacks are coroutines that ``await`` the runtime's answer, so no executor thread is held while a plan
runs; the services' QoS queues (``request_queue_depth``, also the action's goal, result and cancel services) hold
a burst, so the middleware drops no request before the node has seen it. Parameters: :mod:`planning_parameters`
(a run-time change is applied at once, rebuilding the runtime's planning contexts when a planner setting or
``workers`` changes, or rejected with a reason).

The ``plan_motion`` action plans the same way and answers with the service's response as its result; its
:class:`~maru_planner.monitor.PlanMonitor` is published as feedback every ``feedback_period`` and a cancel request
cancels it (:mod:`plan_actions`). Every goal is accepted; one that cannot plan (bad fields, BUSY, no path) ends
ABORTED with the service's error code in its result, a cancelled one CANCELED with the statistics so far.
"""

from __future__ import annotations

import concurrent.futures
import copy
import dataclasses
import itertools
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.planning.queries import query_planners
from maru_planner.robot import RobotModel
from maru_planner.ros import manipulation, parameters
from maru_planner.ros import planning_conversions as conv
from maru_planner.ros import planning_requests as requests
from maru_planner.ros.executor import MultiThreadedExecutor
from maru_planner.ros.lifecycle import ManagedNode, run_node
from maru_planner.ros.markers import MarkerPublisher
from maru_planner.ros.plan_actions import PlanActionServer
from maru_planner.ros.plan_execution import TrajectoryExecution, mark_not_run
from maru_planner.ros.plan_execution import feedback_msg as plan_feedback_msg
from maru_planner.ros.planning_parameters import (
    NODE_PARAMS,
    PLANNER_PREFIX,
    NodeSettings,
    checked_config,
    node_settings,
    parameter_specs,
    planner_config,
    runtime_settings,
)
from maru_planner.ros.robot_description import LATCHED, robot_source, wait_for_robot_description
from maru_planner.runtime import DescriptionFiles, JointStateStore, PlanningRuntime, WorkerPool
from maru_planner.runtime import WorkerContext as PlanningContext
from maru_planner.runtime.robot_loading import DEFAULT_SRDF, DEFAULT_URDF
from maru_planner.runtime.scene_store import DEFAULT_SCENE, SceneStore
from maru_planner.scene import Scene
from maru_planner_interfaces import srv
from maru_planner_interfaces.action import PlanMotion as PlanMotionAction
from maru_planner_interfaces.msg import PlanningError, SceneObstacle

if TYPE_CHECKING:  # the view's module is imported only for a node with a view
    from maru_planner.ros.plan_view_bridge import PlanViewBridge

__all__ = [  # with what moved to the runtime, planning_parameters and robot_description, re-exported
    "DEFAULT_SCENE", "DEFAULT_SRDF", "DEFAULT_URDF", "LATCHED", "NODE_PARAMS", "PLANNER_PREFIX", "NodeSettings",
    "BackgroundPlanningNode", "PlanningContext", "PlanningNode", "SceneStore", "WorkerPool", "main",
    "parameter_specs", "planner_config", "wait_for_robot_description",
]  # fmt: skip

NODE_NAME = "planning_node"
JOINT_STATES_DEPTH = 10  # only the newest state matters; a deep queue of junk messages would only cost memory


class PlanningNode(ManagedNode):
    """Plan, IK and scene services for the upper-body arm planner; a managed node (:mod:`..lifecycle`)."""

    def __init__(self, **kwargs):
        """Raises ``errors.InvalidParameter`` (one line) for a parameter of the wrong type or out of range,
        and with ``autostart`` what configuring raises (robot or scene files)."""
        super().__init__(NODE_NAME, **kwargs)
        self._specs = parameter_specs()
        values = parameters.declare_parameters(self, self._specs)
        self.settings = node_settings(values)
        self.config = checked_config(lambda: planner_config(values))
        self._joint_states = JointStateStore()  # /joint_states; its count of ignored names outlives a cleanup
        self._description_files = DescriptionFiles(prefix=f"{NODE_NAME}_")  # URDF/SRDF given as XML text
        parameters.add_on_set_parameters_callback(self, self._specs, self.when_configured(self._apply_parameters))
        self._view: PlanViewBridge | None = None  # the view option's browser view
        # get_scene's answer: ((scene version, frame), obstacles, YAML); cleared with the runtime it came from
        self._scene_answer_cache: tuple[tuple[int, str], list[SceneObstacle], str] | None = None
        self.start()

    @property
    def ignored_joint_names(self) -> int:
        """/joint_states names the robot does not have (never stored)."""
        return self._joint_states.ignored

    def latest_joint_state(self) -> dict[str, float]:
        return self._joint_states.latest()

    # ------------------------------------------------------------ lifecycle

    def configure(self) -> None:
        """Read the parameters, start the runtime (robot, scene, workers), create topics and services."""
        values = parameters.read_parameters(self, self._specs)
        self.settings = node_settings(values)
        self.config = checked_config(lambda: planner_config(values))
        self._robot_source, origin = robot_source(self, self.settings, self._description_files)
        self._plan_publisher = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="plan_publisher")
        self.runtime = PlanningRuntime(
            self._robot_source, self.settings.scene_file, self.config, runtime_settings(self.settings),
            log=self.get_logger().info, joint_states=self._joint_states,
        )  # fmt: skip
        self._robot = self.runtime.robot  # read-only use in the executor threads (names, markers)
        try:
            self._make_interfaces()
            self._view = self._open_view()
        except BaseException:
            self.runtime.shutdown()
            raise
        self.get_logger().info(
            f"ready: robot {len(self._robot.joint_names)} joints, groups {sorted(self._robot.groups)}, "
            f"scene {len(self.runtime.obstacle_names())} obstacles, "
            f"{self.settings.workers} workers, queue_size {self.settings.queue_size}; {origin}"
        )

    def _open_view(self) -> PlanViewBridge | None:
        """The browser view when the ``view`` parameter is true."""
        if not self.settings.view:
            return None
        # lazy: viser and the web view cost the node ~25 MB and 0.25 s of imports; most nodes run without a view
        from maru_planner.ros.plan_view_bridge import open_view

        return open_view(self, self.runtime, self.settings)

    def activate(self) -> None:
        self._markers.reset_subscribers()  # the marker timer sends the scene to whoever listens now
        if self._description_pub is not None:
            self._description_pub.publish(String(data=Path(self._robot_source.urdf).read_text()))

    def cleanup(self) -> None:
        self._plan_publisher.shutdown(wait=True)  # before the publishers go
        self._scene_answer_cache = None  # the next runtime numbers its scenes from the start
        if self._view is not None:
            self._view.close()
            self._view = None
        self._execution.destroy()  # an action client: not among the entities the lifecycle destroys
        self.runtime.shutdown()  # and forgets the joint values
        self._description_files.cleanup()

    def _make_interfaces(self) -> None:
        services = ReentrantCallbackGroup()
        # rclpy's service default (reliable, volatile, keep last) with a deeper queue: no request dropped
        requests_qos = QoSProfile(
            depth=self.settings.request_queue_depth, history=HistoryPolicy.KEEP_LAST,
            reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE,
        )  # fmt: skip
        for srv_type, name, callback in (
            (srv.PlanMotion, "plan_motion", self._on_plan_motion),
            (srv.ComputeIK, "compute_ik", self._on_compute_ik),
            (srv.ApplyScene, "apply_scene", self._on_apply_scene),
            (srv.GetScene, "get_scene", self._on_get_scene),
            (srv.ComputeFK, "compute_fk", self._on_compute_fk),
            (srv.CheckStateValidity, "check_state_validity", self._on_check_state_validity),
            (srv.QueryPlanners, "query_planners", self._on_query_planners),
            (srv.ComputeCartesianPath, "compute_cartesian_path", self._on_compute_cartesian_path),
        ):
            self.create_managed_service(srv_type, name, callback, qos_profile=requests_qos, callback_group=services)
        self.create_subscription(JointState, "/joint_states", self._on_joint_states, JOINT_STATES_DEPTH,
                                 callback_group=MutuallyExclusiveCallbackGroup())  # fmt: skip
        self.create_subscription(SceneObstacle, "/planning_scene_obstacles", self._on_scene_obstacle, 50,
                                 callback_group=MutuallyExclusiveCallbackGroup())  # fmt: skip
        self._trajectory_pub = self.create_lifecycle_publisher(JointTrajectory, "~/planned_trajectory", LATCHED)
        self._markers = MarkerPublisher(
            self.create_lifecycle_publisher(MarkerArray, "~/markers", 10), self._robot, self.settings.planning_frame,
            scene=lambda: self.runtime.get_scene()[0], now=lambda: self.get_clock().now().to_msg(),
        )  # fmt: skip
        self._description_pub = (
            self.create_lifecycle_publisher(String, "robot_description", LATCHED)
            if self.settings.publish_robot_description
            else None
        )
        self._marker_timer = self.create_timer(
            self.settings.marker_period, self._markers.on_timer, callback_group=MutuallyExclusiveCallbackGroup()
        )
        self._plan_action = PlanActionServer(
            self, PlanMotionAction, "plan_motion",
            plan=lambda goal, monitor: self._answer_plan(goal, PlanMotionAction.Result(), "plan_motion action",
                                                         monitor),
            succeeded=_plan_goal_succeeded, feedback=plan_feedback_msg, period=lambda: self.settings.feedback_period,
            callback_group=services, requests_qos=requests_qos,
        )  # fmt: skip
        self._execution = TrajectoryExecution(self, self.settings, services)  # for goals with execute

    def _apply_parameters(self, changes: dict[str, Any]) -> None:
        """Apply accepted parameter changes (read-only ones never get here: rclpy rejects them); what the
        runtime raises while rebuilding its planning contexts rejects the change, nothing applied."""
        settings = dataclasses.replace(self.settings, **{k: v for k, v in changes.items() if k in NODE_PARAMS})
        config = checked_config(lambda: planner_config(changes, self.config))
        if "execution_action" in changes:
            self._execution.retarget(settings)  # the next execute goal's server (a bad name: rejected)
        rebuilt = self.runtime.reconfigure(config, runtime_settings(settings))
        self.settings, self.config = settings, config
        self._marker_timer.timer_period_ns = int(settings.marker_period * 1e9)
        self.get_logger().info(
            "parameters changed: "
            + ", ".join(f"{k}={v!r}" for k, v in changes.items())
            + (f" (planning contexts rebuilt: {settings.workers} workers)" if rebuilt else "")
        )

    def _awaitable(self, answer: concurrent.futures.Future) -> Future:
        """An rclpy Future a coroutine can await, done when the runtime's ``answer`` is (the executor woken)."""
        future = Future(executor=self.executor)

        def deliver(done: concurrent.futures.Future) -> None:
            try:
                if (error := done.exception()) is not None:
                    future.set_exception(error)
                else:
                    future.set_result(done.result())
            finally:
                if self.executor is not None:
                    self.executor.wake()

        answer.add_done_callback(deliver)
        return future

    # ------------------------------------------------------------ topics

    def _on_joint_states(self, msg: JointState) -> None:
        """Merge the robot's joints of ``msg`` into the latest state; other names are counted, never stored."""
        if len(msg.name) != len(msg.position):
            self.get_logger().warning(
                f"ignoring /joint_states: {len(msg.name)} names but {len(msg.position)} positions",
                throttle_duration_sec=5.0,
            )
            return
        ignored = self.runtime.update_joint_state(msg.name, msg.position)
        if ignored:
            known = self.runtime.joint_names
            unknown = itertools.islice((name for name in msg.name if name not in known), 3)
            self.get_logger().info(
                f"/joint_states: ignored {ignored} unknown or non-finite joint values "
                f"({self.ignored_joint_names} so far), e.g. {', '.join(repr(n[:40]) for n in unknown)}",
                throttle_duration_sec=10.0,
            )

    def _on_scene_obstacle(self, msg: SceneObstacle) -> None:
        try:
            self.runtime.apply_scene(requests.scene_edits([msg], self.settings.planning_frame))
        except errors.MaruError as exc:
            self.get_logger().warning(f"ignoring /planning_scene_obstacles update: {exc}")
            return
        self._markers.publish()

    def _publish_plan(self, trajectory_msg: JointTrajectory, trajectory, start: dict[str, float]) -> None:
        """Publish the last plan on ~/planned_trajectory and, when someone listens, its hand paths."""
        try:
            self._trajectory_pub.publish(trajectory_msg)
            self._markers.publish_plan(trajectory, start, trajectory_msg.header.frame_id, trajectory_msg.header.stamp)
        except Exception as exc:  # noqa: BLE001 - a plan's picture must not take the node down
            self.get_logger().warning(f"the plan was not published: {errors.one_line(exc)}", throttle_duration_sec=10.0)

    # ------------------------------------------------------------ services

    async def _on_plan_motion(self, request: srv.PlanMotion.Request, response: srv.PlanMotion.Response):
        return await self._answer_plan(request, response, "plan_motion")

    def _kinematics(self, request) -> RobotModel | None:
        """The robot for a relative-pose constraint held at the start, with forward-kinematics data of its own
        (requests are converted on several executor threads at once), else None."""
        constraints = request.path_constraints
        if not (constraints.relative_link_a or constraints.relative_link_b):
            return None
        robot = copy.copy(self._robot)
        robot.data = robot.model.createData()
        return robot

    async def _answer_plan(self, request, answer, name: str, monitor: PlanMonitor | None = None):
        """Plan ``request`` (a service request or action goal) and fill ``answer`` (its response or result)."""
        started = time.perf_counter()
        try:
            motion_request = requests.motion_request(
                request, self.settings, self.config.default_planner, self.latest_joint_state, self._kinematics(request)
            )
            result = await self._awaitable(self.runtime.plan(motion_request, monitor))
        except Exception as exc:  # noqa: BLE001 - every failure becomes an error code
            return self._failed(name, answer, exc)
        if self._view is not None:
            self._view.show_result(result, motion_request.start)
        answer.error = conv.result_error_msg(result)
        answer.planning_time = float(getattr(result.stats, "total_time", 0.0) or 0.0)
        answer.stats = conv.stats_msg(result.stats)
        if not result.success:
            self._log_failure(name, answer.error)
            mark_not_run(answer, "the plan failed")
            return answer
        stamp = self.get_clock().now().to_msg()
        answer.trajectory = conv.trajectory_msg(result.trajectory, self.settings.planning_frame, stamp)
        # publishing (and marker FK) on a thread of its own: no executor round on the way to the answer
        self._plan_publisher.submit(
            self._publish_plan, answer.trajectory, result.trajectory, motion_request.start or {}
        )
        self.get_logger().info(
            f"{name} {motion_request.group} {answer.stats.planner_id} on {result.stats.collision_model}: "
            f"{len(answer.trajectory.points)} points, "
            f"core {answer.planning_time:.3f} s, in node {time.perf_counter() - started:.3f} s"
        )
        if not getattr(request, "execute", False):
            mark_not_run(answer, "execute not requested")
        elif not answer.stats.certified:  # executed only when proven collision-free
            mark_not_run(answer, "not executed: the plan is not certified (parameter certify is false)",
                         PlanMotionAction.Result.EXECUTION_NOT_CERTIFIED)  # fmt: skip
        else:
            await self._execution.execute(answer.trajectory, answer, monitor, self.settings)
        return answer

    async def _on_compute_ik(self, request: srv.ComputeIK.Request, response: srv.ComputeIK.Response):
        try:
            ik_request = requests.ik_request(request, self.settings, self.latest_joint_state)
            q = await self._awaitable(self.runtime.compute_ik(ik_request))
        except Exception as exc:  # noqa: BLE001
            return self._failed("compute_ik", response, exc)
        response.error = conv.error_msg(None)
        response.solution = conv.joint_state_msg(self._robot.joint_names, q, self.get_clock().now().to_msg())
        return response

    def _on_apply_scene(self, request: srv.ApplyScene.Request, response: srv.ApplyScene.Response):
        try:
            edits = requests.scene_edits(list(request.obstacles), self.settings.planning_frame)
            response.obstacle_names = self.runtime.apply_scene(edits, clear=request.clear)
        except Exception as exc:  # noqa: BLE001
            response.obstacle_names = self.runtime.obstacle_names()
            return self._failed("apply_scene", response, exc, source="scene")
        response.error = conv.error_msg(None)
        self._markers.publish()
        return response

    def _on_get_scene(self, _request: srv.GetScene.Request, response: srv.GetScene.Response):
        response.obstacles, response.scene_yaml = self._scene_answer()
        return response

    def _scene_answer(self) -> tuple[list[SceneObstacle], str]:
        """get_scene's obstacles and YAML, made again only when the scene (its version) or the frame changed."""
        frame = self.settings.planning_frame
        cached = self._scene_answer_cache
        if cached is None or cached[0] != (self.runtime.scene_version, frame):
            scene_dict, version = self.runtime.get_scene()
            obstacles = [conv.obstacle_to_msg(o, frame) for o in scene_dict.get("obstacles", [])]
            cached = self._scene_answer_cache = ((version, frame), obstacles, Scene.from_dict(scene_dict).to_yaml())
        return cached[1], cached[2]

    # ------------------------------------------------------------ manipulation services (docs/manipulation.md)

    async def _on_compute_fk(self, request: srv.ComputeFK.Request, response: srv.ComputeFK.Response):
        try:
            values = requests.start_state(request.robot_state, self.latest_joint_state)
            poses = await self._awaitable(self.runtime.compute_fk(values, list(request.links)))
        except Exception as exc:  # noqa: BLE001 - every failure becomes an error code
            return self._failed("compute_fk", response, exc)
        response.error = conv.error_msg(None)
        manipulation.fill_fk(response, poses, self.settings.planning_frame, self.get_clock().now().to_msg())
        return response

    async def _on_check_state_validity(self, request: srv.CheckStateValidity.Request, response):
        try:
            values = requests.start_state(request.robot_state, self.latest_joint_state)
            constraints = manipulation.path_constraints(request.constraints, self.settings.planning_frame)
            answer = await self._awaitable(self.runtime.check_state_validity(values, constraints))
        except Exception as exc:  # noqa: BLE001
            return self._failed("check_state_validity", response, exc)
        response.error = conv.error_msg(None)
        manipulation.fill_validity(response, answer)
        return response

    def _on_query_planners(self, _request: srv.QueryPlanners.Request, response: srv.QueryPlanners.Response):
        config = self.config
        manipulation.fill_planners(response, query_planners(config.planner_params), config.default_planner)
        return response

    async def _on_compute_cartesian_path(self, request: srv.ComputeCartesianPath.Request, response):
        settings = self.settings
        try:
            start = requests.start_state(request.start_state, self.latest_joint_state)
            cartesian = manipulation.cartesian_request(
                request, start, settings.default_group, settings.planning_frame, settings.max_planning_time
            )
            result = await self._awaitable(self.runtime.cartesian_path(cartesian))
        except Exception as exc:  # noqa: BLE001
            return self._failed("compute_cartesian_path", response, exc)
        manipulation.fill_cartesian(response, result, settings.planning_frame, self.get_clock().now().to_msg())
        if not result.success:
            self._log_failure("compute_cartesian_path", response.error)
        return response

    def _failed(self, service: str, response: Any, exc: BaseException, source: str = "node") -> Any:
        """``response`` (or action result) with ``exc`` as its error, logged."""
        response.error = conv.error_msg(exc, source=source)
        mark_not_run(response, "the plan failed")
        self._log_failure(service, response.error)
        return response

    def _log_failure(self, service: str, error: PlanningError) -> None:
        self.get_logger().warning(f"{service}: {conv.code_name(error.code)}: {error.message}")


def _plan_goal_succeeded(result: PlanMotionAction.Result) -> bool:
    """A plan goal succeeded: planned, and executed when asked to (not run: not asked)."""
    executed = result.execution_error_code in (0, PlanMotionAction.Result.EXECUTION_NOT_RUN)
    return result.error.code == PlanningError.SUCCESS and executed


class BackgroundPlanningNode:
    """``planning_node`` spun by its own executor in a daemon thread of this process.

    For demos and scripts that want the node without a subprocess; rclpy must already be
    initialised. Keyword arguments override parameters::

        with BackgroundPlanningNode(default_planner="PRM", scene_file="none") as planning:
            ...  # call its services, e.g. with maru_planner.ros.planning_client.PlanningClient
    """

    def __init__(self, namespace: str = "", **overrides: Any):
        parameter_overrides = [Parameter(name, value=value) for name, value in overrides.items()]
        self.node = PlanningNode(namespace=namespace, parameter_overrides=parameter_overrides)
        self.executor = MultiThreadedExecutor(num_threads=self.node.settings.executor_threads)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self.executor.spin, name="planning_node", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self.executor.shutdown(timeout_sec=5.0)
        self._thread.join(timeout=5.0)  # before destroying: a pending publish task must not hit a dead node
        self.node.destroy_node()

    def __enter__(self) -> BackgroundPlanningNode:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run maru_planner planning_node`` (and ``python -m``); exit code 2 on bad start-up input."""
    return run_node(
        NODE_NAME,
        PlanningNode,
        args,
        startup_errors=(errors.MaruError, OSError, ValueError),  # parameters, robot or scene files
        executor_threads=lambda node: node.settings.executor_threads,
    )


if __name__ == "__main__":
    sys.exit(main())
