"""``planning_node``: ROS 2 services around the arm-planning core.

A thin adapter: messages are converted in :mod:`planning_conversions`, the
work is done by the core (``MotionPlanner``, ``solve_ik``, ``Scene``).

Parameters are declared from :class:`NodeSettings` (the node's own), the fields of
:class:`~maru_planner.planning.PlannerConfig` and, per registered planner, its parameters as
``planners.<ID>.<name>`` (:mod:`maru_planner.planning.registry`); each has a descriptor with its
type, range and description. A run-time change is applied at once (the planning contexts are
rebuilt when a planner setting or ``workers`` changes, so the next answer uses it) or rejected
with a reason (read-only ones: the robot, the start-up scene, the frame, executor threads).

Concurrency and admission: service callbacks are coroutines. They hand the core call to a
:class:`WorkerPool` of ``workers`` threads, each owning its own robot model, collision checker
and planner (pinocchio data and OMPL set-ups are not shared between threads), and ``await``
the answer, so no executor thread is held while a plan runs. With ``worker_processes`` (the
default) each thread hands its plan to one of ``workers`` worker processes
(:class:`~maru_planner.planning.process_pool.ProcessPool`: own OMPL, model and scene, brought to the
node's scene before the next plan), so concurrent plans run on every core; threads alone take turns
in OMPL (one process-wide lock). At most ``workers + queue_size``
requests are admitted (planning or waiting); one more is answered BUSY at once. Time spent
waiting counts against the request's own budget. The services' QoS queue
(``request_queue_depth``) is deeper than that, so the middleware drops no request before the
node has seen it.

The ``plan_motion`` action (``maru_planner_interfaces/action/PlanMotion``) plans the same way,
through the same conversion and worker pool, and answers with the service's response as its
result. While a goal runs, its :class:`~maru_planner.monitor.PlanMonitor` is published as feedback
every ``feedback_period``; a cancel request cancels the monitor, which stops the search at once.
Every goal is accepted; one that cannot plan (bad fields, BUSY, no path) ends ABORTED with the
service's error code in its result, a cancelled one CANCELED with the statistics so far.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import math
import queue
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from rclpy.wait_for_message import wait_for_message
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from maru_planner import errors
from maru_planner.collision import sphere_model
from maru_planner.monitor import PlanMonitor, Progress
from maru_planner.params import ParamSpec, dataclass_params, param
from maru_planner.paths import config_path, urdf_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, timing
from maru_planner.planning.config import PLANNER_CONFIG_PARAMS
from maru_planner.planning.process_pool import ProcessPool, RobotSource
from maru_planner.planning.queries import query_planners
from maru_planner.planning.registry import PLANNERS
from maru_planner.planning.warm_up import warm_up
from maru_planner.robot import RobotModel
from maru_planner.robot.ik import solve_ik
from maru_planner.ros import manipulation, parameters
from maru_planner.ros import planning_conversions as conv
from maru_planner.ros.lifecycle import ManagedNode, run_node
from maru_planner.ros.markers import plan_markers, scene_markers
from maru_planner.ros.plan_actions import PlanActionServer
from maru_planner.scene import Obstacle, Scene
from maru_planner_interfaces.action import PlanMotion as PlanMotionAction
from maru_planner_interfaces.msg import PlanningError, SceneObstacle
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

NODE_NAME = "planning_node"
DEFAULT_URDF = "maru1_upper_body.urdf"
DEFAULT_SRDF = "maru1_upper_body.srdf"
DEFAULT_SCENE = "scenes/maru13_desk_box.yaml"
PLANNER_PREFIX = "planners"

LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
JOINT_STATES_DEPTH = 10  # only the newest state matters; a deep queue of junk messages would only cost memory


@dataclass
class NodeSettings:
    """The node's own settings (the planner's are ``PlannerConfig``'s); each is a ROS parameter."""

    robot_urdf: str = param("", "URDF file; empty = the package's urdf/maru1_upper_body.urdf", read_only=True)
    robot_srdf: str = param("", "SRDF file; empty = the package's urdf/maru1_upper_body.srdf", read_only=True)
    package_dirs: list[str] = param(
        default_factory=list, description="extra directories that resolve package:// mesh URIs", read_only=True
    )
    robot_description: str = param(
        "", "URDF XML as robot_state_publisher takes it; set: used instead of robot_urdf", read_only=True
    )
    robot_description_semantic: str = param(
        "", "SRDF XML (MoveIt's parameter); set: used instead of robot_srdf", read_only=True
    )
    robot_description_source: str = param(
        "parameter",
        "where the URDF comes from: parameter (robot_description if set, else robot_urdf) or topic (the "
        "latched robot_description topic of robot_state_publisher, waited for when configuring)",
        choices=("parameter", "topic"),
        read_only=True,
    )
    robot_description_timeout: float = param(
        10.0, "s configuring waits for the robot_description topic (source topic)", lower=0.1, upper=3600.0
    )
    publish_robot_description: bool = param(
        False,
        "publish the URDF on the latched robot_description topic, for setups without robot_state_publisher",
        read_only=True,
    )
    planning_frame: str = param(
        "base_link", "frame of goal poses, obstacles, trajectories and markers (the URDF root)", read_only=True
    )
    default_group: str = param("upper_body", "planning group used when a request leaves group empty")
    max_planning_time: float = param(
        60.0,
        "largest allowed_planning_time a request may ask for (s); more is INVALID_REQUEST",
        lower=0.01,
        upper=3600.0,
    )
    default_attempts: int = param(1, "num_attempts used when a request gives 0", lower=1, upper=1000)
    ik_timeout: float = param(1.0, "compute_ik budget when the request gives none (s)", lower=0.001, upper=60.0)
    scene_file: str = param(
        "",
        "start-up scene; empty = config/scenes/maru13_desk_box.yaml, none = empty scene; "
        "a relative path is looked up in the working directory, then in the package's config/",
        read_only=True,
    )
    workers: int = param(2, "planning threads, each with its own robot model, checker and planner", lower=1, upper=32)
    worker_processes: bool = param(
        True,
        "each planning thread hands its plans to a worker process (own OMPL, robot model and scene), so "
        "concurrent plans use every core; false: plans run in the threads, whose OMPL searches take turns",
        read_only=True,
    )
    queue_size: int = param(
        16, "requests admitted to wait for a busy worker; beyond workers + queue_size: BUSY", lower=0, upper=1024
    )
    request_queue_depth: int = param(
        256,
        "QoS depth of the service request queues (requests the middleware holds until the node takes them)",
        lower=1,
        upper=100000,
        read_only=True,
    )
    executor_threads: int = param(
        4, "executor threads for callbacks (services never hold one while planning)", lower=2, upper=64, read_only=True
    )
    marker_period: float = param(
        1.0, "how often a new ~/markers subscriber is looked for, to send it the scene (s)", lower=0.01, upper=60.0
    )
    feedback_period: float = param(
        0.1, "seconds between plan_motion action feedback messages (at most 0.2: at least 5 Hz)", lower=0.01, upper=0.2
    )


NODE_PARAMS: dict[str, ParamSpec] = dataclass_params(NodeSettings)


def parameter_specs() -> dict[str, ParamSpec]:
    """Every parameter of the node: its settings, ``PlannerConfig``'s, ``planners.<ID>.<name>`` per planner."""
    specs = {**NODE_PARAMS, **PLANNER_CONFIG_PARAMS}
    specs["default_planner"] = dataclasses.replace(specs["default_planner"], choices=tuple(PLANNERS))
    for planner_id, planner in PLANNERS.items():
        specs.update(parameters.prefixed(planner.params, f"{PLANNER_PREFIX}.{planner_id}"))
    return specs


def planner_config(values: dict[str, Any], base: PlannerConfig | None = None) -> PlannerConfig:
    """``base`` (else the defaults) with the config fields and ``planners.<ID>.<name>`` found in ``values``."""
    base = base or PlannerConfig()
    fields = {name: value for name, value in values.items() if name in PLANNER_CONFIG_PARAMS}
    planner_params = copy.deepcopy(base.planner_params)
    for name, value in values.items():
        if name.startswith(PLANNER_PREFIX + "."):
            _, planner_id, key = name.split(".", 2)
            planner_params.setdefault(planner_id, {})[key] = value
    return dataclasses.replace(base, **fields, planner_params=planner_params)


@dataclass
class PlanningContext:
    """Everything one worker thread needs to plan: its own planner (robot model, checker) at ``scene_version``.

    With ``processes`` (``worker_processes``), plans go to those worker processes; the thread's own
    planner answers IK, FK and validity checks.
    """

    planner: MotionPlanner
    scene_version: int
    processes: ProcessPool | None = None


class WorkerPool:
    """Planning threads, one :class:`PlanningContext` each, behind a bounded admission count.

    ``submit`` admits a job while fewer than ``len(contexts) + queue_size`` are planning or
    waiting, else raises ``errors.Busy`` at once. ``close`` lets the admitted jobs finish,
    then the threads end (the node swaps in a new pool when its planner settings change).
    """

    def __init__(self, contexts: list[PlanningContext], queue_size: int, name: str = "planner"):
        self.queue_size = queue_size
        self._jobs: queue.SimpleQueue[Callable[[PlanningContext], None] | None] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._admitted = 0
        self._threads = [
            threading.Thread(target=self._serve, args=(context,), name=f"{name}-{i}", daemon=True)
            for i, context in enumerate(contexts)
        ]
        for thread in self._threads:
            thread.start()

    @property
    def workers(self) -> int:
        return len(self._threads)

    def submit(self, job: Callable[[PlanningContext], None]) -> None:
        """Queue ``job(context)`` for the next free worker; errors.Busy if the queue is full."""
        with self._lock:
            capacity = self.workers + self.queue_size
            if self._admitted >= capacity:
                raise errors.Busy(
                    f"{self._admitted} requests are planning or waiting (workers {self.workers} + "
                    f"queue_size {self.queue_size}); try again later"
                )
            self._admitted += 1
        self._jobs.put(job)

    def close(self) -> None:
        """Finish the admitted jobs, then stop the threads (no new job may be submitted)."""
        for _ in self._threads:
            self._jobs.put(None)

    def _serve(self, context: PlanningContext) -> None:
        while (job := self._jobs.get()) is not None:
            try:
                job(context)
            finally:
                with self._lock:
                    self._admitted -= 1


class SceneStore:
    """The node's planning scene, changed atomically; readers get copies."""

    def __init__(self, scene_dict: dict):
        self._lock = threading.Lock()
        self._scene = Scene.from_dict(scene_dict)
        self.version = 0

    def snapshot(self) -> tuple[dict, int]:
        with self._lock:
            return copy.deepcopy(self._scene.to_dict()), self.version

    def apply(
        self, obstacles: list[SceneObstacle], clear: bool, frame: str, attachments: manipulation.Attachments
    ) -> list[str]:
        """Apply ADD/MOVE/REMOVE operations (after an optional clear) all-or-nothing; return the names.

        Obstacle poses must be in ``frame`` (the planning frame) or have an empty frame_id.
        """
        with self._lock:
            scene = Scene.from_dict(copy.deepcopy(self._scene.to_dict()))
            if clear:
                scene.clear()
            for msg in obstacles:
                _apply_obstacle(scene, msg, frame, attachments)
            attachments.check(scene)
            self._scene = scene
            self.version += 1
            return [o["name"] for o in scene.to_dict().get("obstacles", [])]


def _apply_obstacle(scene, msg: SceneObstacle, frame: str, attachments: manipulation.Attachments) -> None:
    """One ADD/MOVE/REMOVE/ATTACH/DETACH on ``scene`` (raises InvalidScene naming the obstacle)."""
    if not msg.name:
        raise errors.InvalidScene("obstacle has an empty name")
    if msg.operation != SceneObstacle.REMOVE and msg.header.frame_id not in ("", frame):
        raise errors.InvalidScene(
            f"obstacle '{msg.name}' is in frame '{msg.header.frame_id}'; only '{frame}' is supported (no tf here)"
        )
    if msg.operation == SceneObstacle.REMOVE:
        scene.remove(msg.name)
    elif msg.operation == SceneObstacle.MOVE:
        scene.move(msg.name, conv.obstacle_pose(msg.pose, msg.name))
    elif msg.operation == SceneObstacle.ADD:
        scene.add(Obstacle.from_dict(conv.primitive_to_obstacle(msg.name, msg.shape, msg.pose)))
    elif msg.operation in (SceneObstacle.ATTACH, SceneObstacle.DETACH):
        manipulation.apply_attachment(scene, msg, frame, attachments.link_pose)
    else:
        raise errors.InvalidScene(
            f"obstacle '{msg.name}': operation {msg.operation} is not ADD, MOVE, REMOVE, ATTACH or DETACH"
        )


class PlanningNode(ManagedNode):
    """Plan, IK and scene services for the upper-body arm planner; a managed node (:mod:`..lifecycle`)."""

    def __init__(self, **kwargs):
        """Raises ``errors.InvalidParameter`` (one line) for a parameter of the wrong type or out of range,
        and with ``autostart`` what configuring raises (robot or scene files)."""
        super().__init__(NODE_NAME, **kwargs)
        self._specs = parameter_specs()
        values = parameters.declare_parameters(self, self._specs)
        self.settings = NodeSettings(**{name: values[name] for name in NODE_PARAMS})
        self.config = _checked_config(lambda: planner_config(values))
        self._latest_joints: dict[str, float] = {}
        self._joints_lock = threading.Lock()
        self.ignored_joint_names = 0  # /joint_states names the robot does not have (never stored)
        self._last_plan_markers = None
        self._marker_lock = threading.Lock()  # plan_markers uses self._robot's shared pinocchio data
        self._marker_subscribers = 0
        self._pool_lock = threading.Lock()
        self._processes: ProcessPool | None = None  # worker_processes: kept (reconfigured) across pool rebuilds
        self._description_dir: tempfile.TemporaryDirectory | None = None  # URDF/SRDF given as XML text
        parameters.add_on_set_parameters_callback(self, self._specs, self.when_configured(self._apply_parameters))
        self.start()

    # ------------------------------------------------------------ lifecycle

    def configure(self) -> None:
        """Read the parameters, load the robot and scene, start the workers, create topics and services."""
        values = parameters.read_parameters(self, self._specs)
        self.settings = NodeSettings(**{name: values[name] for name in NODE_PARAMS})
        self.config = _checked_config(lambda: planner_config(values))
        self._description_files = self._robot_description_files()
        self._robot = self._make_robot()  # read-only use in the executor threads (names, markers)
        self._joint_names = frozenset(self._robot.joint_names)
        self._attachments = manipulation.Attachments(self._robot, self.latest_joint_state)
        _check_group(self._robot, self.settings.default_group)
        self._scene = SceneStore(self._load_scene_dict())
        self._pool = self._make_pool(self.config, self.settings)
        self._make_interfaces()
        self.get_logger().info(
            f"ready: robot {len(self._robot.joint_names)} joints, groups {sorted(self._robot.groups)}, "
            f"scene {len(self._scene.snapshot()[0].get('obstacles', []))} obstacles, "
            f"{self.settings.workers} workers, queue_size {self.settings.queue_size}; {self._description_origin}"
        )

    def activate(self) -> None:
        self._marker_subscribers = 0  # the marker timer sends the scene to whoever listens now
        if self._description_pub is not None:
            self._description_pub.publish(String(data=Path(self._robot_files()[0]).read_text()))

    def cleanup(self) -> None:
        with self._pool_lock:
            self._pool.close()
            if self._processes is not None:
                self._processes.close()
        with self._joints_lock:
            self._latest_joints.clear()
        self._last_plan_markers = None
        if self._description_dir is not None:
            self._description_dir.cleanup()
            self._description_dir = None

    # ------------------------------------------------------------ set-up

    def _robot_files(self) -> tuple[str, str, list[str]]:
        urdf, srdf = self._description_files
        return urdf, srdf, [d for d in self.settings.package_dirs if d]

    def _robot_description_files(self) -> tuple[str, str]:
        """URDF and SRDF files: robot_description(_semantic) XML written to a private directory, else the files."""
        settings = self.settings
        if settings.robot_description_source == "topic" and settings.publish_robot_description:
            raise errors.InvalidParameter(
                "publish_robot_description would echo the robot_description topic it reads "
                "(robot_description_source topic); set one of them"
            )
        urdf_xml, urdf_from = settings.robot_description, "the robot_description parameter"
        if settings.robot_description_source == "topic":
            urdf_xml = wait_for_robot_description(self, settings.robot_description_timeout)
            urdf_from = "topic " + self.resolve_topic_name("robot_description")
        urdf = self._written("robot_description.urdf", urdf_xml) if urdf_xml else settings.robot_urdf
        srdf_xml = settings.robot_description_semantic
        srdf = self._written("robot_description_semantic.srdf", srdf_xml) if srdf_xml else settings.robot_srdf
        urdf, srdf = urdf or str(urdf_path(DEFAULT_URDF)), srdf or str(urdf_path(DEFAULT_SRDF))
        self._description_origin = (
            f"URDF from {urdf_from if urdf_xml else urdf}, "
            f"SRDF from {'the robot_description_semantic parameter' if srdf_xml else srdf}"
        )
        return urdf, srdf

    def _written(self, name: str, text: str) -> str:
        if self._description_dir is None:
            self._description_dir = tempfile.TemporaryDirectory(prefix=f"{NODE_NAME}_")
        path = Path(self._description_dir.name) / name
        path.write_text(text)
        return str(path)

    def _make_robot(self) -> RobotModel:
        urdf, srdf, package_dirs = self._robot_files()
        return RobotModel.from_urdf(urdf, srdf, package_dirs=package_dirs or None)

    def _make_context(self, config: PlannerConfig, processes: ProcessPool | None) -> PlanningContext:
        scene_dict, version = self._scene.snapshot()
        planner = MotionPlanner.from_scene(self._make_robot(), Scene.from_dict(scene_dict), config)
        return PlanningContext(planner, version, processes)

    def _make_pool(self, config: PlannerConfig, settings: NodeSettings) -> WorkerPool:
        if config.collision_model == "spheres":
            self._fit_spheres_once()
        processes = self._reconfigured_processes(config, settings)
        contexts = [self._make_context(config, processes) for _ in range(settings.workers)]
        if processes is not None:
            processes.wait_ready()  # the workers build their planners and warm up meanwhile, in parallel
            for n, summary in enumerate(processes.warm_ups()):
                self.get_logger().info(f"worker process {n}: {summary}")
        else:  # no request pays numba's compile or cache load (warm_up module doc)
            self.get_logger().info(warm_up(contexts[0].planner.robot, config).summary())
        return WorkerPool(contexts, settings.queue_size)

    def _fit_spheres_once(self) -> None:
        """Fit the robot's sphere model here, once per geometry (disk-cached), so the planners and worker processes
        built next load it instead of each fitting it at the same time."""
        robot = self._robot
        notice = sphere_model.first_fit_notice(robot.name, robot.collision_model)
        if notice:
            self.get_logger().info(notice)
        sphere_model.load_or_fit(robot.model, robot.collision_model)

    def _reconfigured_processes(self, config: PlannerConfig, settings: NodeSettings) -> ProcessPool | None:
        """The worker processes (``worker_processes``), started once, then given ``config`` and ``workers``."""
        if not settings.worker_processes:
            return None
        if self._processes is None or self._processes.closed:
            urdf, srdf, package_dirs = self._robot_files()
            scene_dict, version = self._scene.snapshot()
            source = RobotSource(urdf, srdf, tuple(package_dirs))
            self._processes = ProcessPool(source, scene_dict, config, settings.workers, scene_version=version)
        else:
            self._processes.set_config(config)
            self._processes.resize(settings.workers)
        return self._processes

    def _load_scene_dict(self) -> dict:
        scene_file = self.settings.scene_file
        if scene_file.lower() == "none":
            return Scene().to_dict()
        path = Path(scene_file) if scene_file else config_path(DEFAULT_SCENE)
        if not path.is_absolute() and not path.is_file():
            path = config_path(scene_file)  # e.g. "scenes/maru6_desk.yaml" from the package's config/
        return Scene.from_yaml(path).to_dict()

    def _make_interfaces(self) -> None:
        services = ReentrantCallbackGroup()
        # rclpy's service default (reliable, volatile, keep last) with a deeper queue: no request dropped
        requests = QoSProfile(
            depth=self.settings.request_queue_depth,
            history=HistoryPolicy.KEEP_LAST,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.VOLATILE,
        )
        for srv_type, name, callback in (
            (PlanMotion, "plan_motion", self._on_plan_motion),
            (ComputeIK, "compute_ik", self._on_compute_ik),
            (ApplyScene, "apply_scene", self._on_apply_scene),
            (GetScene, "get_scene", self._on_get_scene),
            (ComputeFK, "compute_fk", self._on_compute_fk),
            (CheckStateValidity, "check_state_validity", self._on_check_state_validity),
            (QueryPlanners, "query_planners", self._on_query_planners),
            (ComputeCartesianPath, "compute_cartesian_path", self._on_compute_cartesian_path),
        ):
            self.create_managed_service(srv_type, name, callback, qos_profile=requests, callback_group=services)
        self.create_subscription(
            JointState,
            "/joint_states",
            self._on_joint_states,
            JOINT_STATES_DEPTH,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )
        self.create_subscription(
            SceneObstacle,
            "/planning_scene_obstacles",
            self._on_scene_obstacle,
            50,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )
        self._trajectory_pub = self.create_lifecycle_publisher(JointTrajectory, "~/planned_trajectory", LATCHED)
        self._marker_pub = self.create_lifecycle_publisher(MarkerArray, "~/markers", 10)
        self._description_pub = (
            self.create_lifecycle_publisher(String, "robot_description", LATCHED)
            if self.settings.publish_robot_description
            else None
        )
        self._marker_timer = self.create_timer(
            self.settings.marker_period, self._on_marker_timer, callback_group=MutuallyExclusiveCallbackGroup()
        )
        self._make_plan_action(services, requests)

    def _make_plan_action(self, callback_group: ReentrantCallbackGroup, requests: QoSProfile) -> None:
        self._plan_action = PlanActionServer(
            self,
            PlanMotionAction,
            "plan_motion",
            plan=lambda goal, monitor: self._answer_plan(
                goal, PlanMotionAction.Result(), "plan_motion action", monitor
            ),
            succeeded=lambda result: result.error.code == PlanningError.SUCCESS,
            feedback=_feedback_msg,
            period=lambda: self.settings.feedback_period,
            callback_group=callback_group,
            requests_qos=requests,
        )

    # ------------------------------------------------------------ run-time parameter changes

    def _apply_parameters(self, changes: dict[str, Any]) -> None:
        """Apply accepted parameter changes (read-only ones never get here: rclpy rejects them).

        A planner setting or ``workers`` builds a new worker pool first (raising rejects the
        change, nothing is applied); requests already admitted finish on the old one.
        """
        settings = dataclasses.replace(self.settings, **{k: v for k, v in changes.items() if k in NODE_PARAMS})
        config = _checked_config(lambda: planner_config(changes, self.config))
        _check_group(self._robot, settings.default_group)
        rebuild = config != self.config or settings.workers != self.settings.workers
        pool = self._make_pool(config, settings) if rebuild else None
        with self._pool_lock:
            self.settings, self.config = settings, config
            if pool is not None:
                self._pool, old = pool, self._pool
                old.close()
            self._pool.queue_size = settings.queue_size
        self._marker_timer.timer_period_ns = int(settings.marker_period * 1e9)
        self.get_logger().info(
            "parameters changed: "
            + ", ".join(f"{k}={v!r}" for k, v in changes.items())
            + (f" (planning contexts rebuilt: {settings.workers} workers)" if rebuild else "")
        )

    # ------------------------------------------------------------ worker pool

    def _in_worker(self, fn, *args) -> Future:
        """Run ``fn(context, *args)`` on a planning worker; an rclpy Future a coroutine can await.

        Raises ``errors.Busy`` at once when the admission queue is full.
        """
        future = Future(executor=self.executor)

        def job(context: PlanningContext) -> None:
            try:
                self._sync_scene(context)
                future.set_result(fn(context, *args))
            except BaseException as exc:  # noqa: BLE001 - handed to the awaiting callback
                future.set_exception(exc)
            finally:
                if self.executor is not None:
                    self.executor.wake()

        with self._pool_lock:
            self._pool.submit(job)
        return future

    def _sync_scene(self, context: PlanningContext) -> None:
        """Bring the context's planner (and the worker processes) to the node's latest scene."""
        processes = context.processes
        latest = self._scene.version
        if context.scene_version == latest and (processes is None or processes.scene_version >= latest):
            return
        scene_dict, version = self._scene.snapshot()
        if context.scene_version != version:
            context.planner.set_scene(Scene.from_dict(scene_dict))
            context.scene_version = version
        if processes is not None:
            processes.set_scene(scene_dict, version)

    # ------------------------------------------------------------ topics

    def _on_joint_states(self, msg: JointState) -> None:
        """Merge the robot's joints of ``msg`` into the latest state; other names are counted, never stored."""
        if len(msg.name) != len(msg.position):
            self.get_logger().warning(
                f"ignoring /joint_states: {len(msg.name)} names but {len(msg.position)} positions",
                throttle_duration_sec=5.0,
            )
            return
        known = self._joint_names
        values = {n: float(v) for n, v in zip(msg.name, msg.position) if n in known and math.isfinite(v)}
        ignored = len(msg.name) - len(values)
        with self._joints_lock:
            self._latest_joints.update(values)
            self.ignored_joint_names += ignored
        if ignored:
            unknown = itertools.islice((name for name in msg.name if name not in known), 3)
            self.get_logger().info(
                f"/joint_states: ignored {ignored} unknown or non-finite joint values "
                f"({self.ignored_joint_names} so far), e.g. {', '.join(repr(n[:40]) for n in unknown)}",
                throttle_duration_sec=10.0,
            )

    def latest_joint_state(self) -> dict[str, float]:
        with self._joints_lock:
            return dict(self._latest_joints)

    def _on_scene_obstacle(self, msg: SceneObstacle) -> None:
        try:
            self._scene.apply([msg], clear=False, frame=self.settings.planning_frame, attachments=self._attachments)
        except errors.MaruError as exc:
            self.get_logger().warning(f"ignoring /planning_scene_obstacles update: {exc}")
            return
        self._publish_markers()

    def _on_marker_timer(self) -> None:
        count = self._marker_pub.get_subscription_count()
        if count > self._marker_subscribers:
            self._publish_markers()
        self._marker_subscribers = count

    def _publish_markers(self) -> None:
        if self._marker_pub.get_subscription_count() == 0:
            return
        frame = self.settings.planning_frame
        markers = scene_markers(self._scene.snapshot()[0], frame, self.get_clock().now().to_msg())
        with self._marker_lock:
            if self._last_plan_markers is not None:
                markers.markers.extend(self._last_plan_markers.markers)
        self._marker_pub.publish(markers)

    # ------------------------------------------------------------ services

    async def _on_plan_motion(self, request: PlanMotion.Request, response: PlanMotion.Response):
        return await self._answer_plan(request, response, "plan_motion")

    async def _answer_plan(self, request, answer, name: str, monitor: PlanMonitor | None = None):
        """Plan ``request`` (a service request or action goal) and fill ``answer`` (its response or result)."""
        started = time.perf_counter()
        try:
            motion_request = self._motion_request(request)
            deadline = time.monotonic() + motion_request.time_budget
            result = await self._in_worker(_plan_in_context, motion_request, deadline, monitor)
        except Exception as exc:  # noqa: BLE001 - every failure becomes an error code
            return self._failed(name, answer, exc)
        answer.error = conv.result_error_msg(result)
        answer.planning_time = float(getattr(result.stats, "total_time", 0.0) or 0.0)
        answer.stats = conv.stats_msg(result.stats)
        if not result.success:
            self._log_failure(name, answer.error)
            return answer
        stamp = self.get_clock().now().to_msg()
        answer.trajectory = conv.trajectory_msg(result.trajectory, self.settings.planning_frame, stamp)
        # publishing (and marker FK) happens after the answer has gone out
        assert self.executor is not None  # a service callback runs in the node's executor
        self.executor.create_task(self._publish_plan, answer.trajectory, result.trajectory, motion_request.start)
        self.get_logger().info(
            f"{name} {motion_request.group} {answer.stats.planner_id} on {result.stats.collision_model}: "
            f"{len(answer.trajectory.points)} points, "
            f"core {answer.planning_time:.3f} s, in node {time.perf_counter() - started:.3f} s"
        )
        return answer

    def _publish_plan(self, trajectory_msg: JointTrajectory, trajectory, start: dict[str, float]) -> None:
        """Publish the last plan on ~/planned_trajectory and, when someone listens, its hand paths."""
        self._trajectory_pub.publish(trajectory_msg)
        if self._marker_pub.get_subscription_count() > 0:
            frame = trajectory_msg.header.frame_id
            with self._marker_lock:
                self._last_plan_markers = plan_markers(
                    self._robot, trajectory, start, frame, trajectory_msg.header.stamp
                )
            self._publish_markers()

    def _motion_request(self, request: PlanMotion.Request | PlanMotionAction.Goal) -> MotionRequest:
        """Core ``MotionRequest`` of a ``PlanMotion`` request or goal (raises typed errors for bad fields)."""
        settings = self.settings
        budget = float(request.allowed_planning_time)
        if not math.isfinite(budget) or budget <= 0.0:
            raise errors.InvalidRequest(f"allowed_planning_time must be > 0 s, got {budget}")
        if budget > settings.max_planning_time:
            raise errors.InvalidRequest(
                f"allowed_planning_time {budget} s exceeds max_planning_time {settings.max_planning_time} s"
            )
        start = self._start_state(request.start_state)
        goal_joints = None
        if request.goal_joint_names or request.goal_positions:
            goal_joints = conv.named_values(request.goal_joint_names, request.goal_positions, "goal")
        goal_poses = None
        if request.goal_poses or request.goal_links:
            goal_poses = conv.pose_goals(request.goal_poses, request.goal_links, settings.planning_frame)
        if goal_joints is None and goal_poses is None:
            raise errors.InvalidRequest("no goal: give goal_joint_names + goal_positions or goal_poses + goal_links")
        if goal_joints is not None and goal_poses is not None:
            raise errors.InvalidRequest("give either a joint goal or pose goals, not both")
        # kept along the motion; planned by CBiRRT, which an empty planner id then means
        constraints = manipulation.path_constraints(request.path_constraints, settings.planning_frame)
        return MotionRequest(
            group=request.group or settings.default_group,
            start=start,
            goal_joints=goal_joints,
            goal_poses=goal_poses,
            planner_id=request.planner_id or ("" if not constraints.empty else self.config.default_planner),
            time_budget=budget,
            seed=None if request.seed < 0 else int(request.seed),
            attempts=int(request.num_attempts) if request.num_attempts > 0 else settings.default_attempts,
            velocity_scaling=_scaling(request.max_velocity_scaling_factor, "max_velocity_scaling_factor"),
            acceleration_scaling=_scaling(request.max_acceleration_scaling_factor, "max_acceleration_scaling_factor"),
            time_parameterization=request.time_parameterization,
            jerk_scaling=_scaling(request.max_jerk_scaling_factor, "max_jerk_scaling_factor"),
            path_constraints=constraints,
        )

    def _start_state(self, msg: JointState) -> dict[str, float]:
        if msg.name or msg.position:
            return conv.joint_state_values(msg, "start_state")
        latest = self.latest_joint_state()
        if not latest:
            raise errors.NoStartState("start_state is empty and no /joint_states message has been received")
        return latest

    async def _on_compute_ik(self, request: ComputeIK.Request, response: ComputeIK.Response):
        try:
            targets = conv.pose_goals(request.poses, request.links, self.settings.planning_frame)
            if not targets:
                raise errors.InvalidRequest("no poses: give poses + links")
            seed, strict = self._ik_seed(request.seed_state)
            timeout = _ik_timeout(request.timeout, self.settings)
            group = request.group or self.settings.default_group
            deadline = time.monotonic() + timeout
            q = await self._in_worker(_ik_in_context, group, targets, seed, strict, deadline, request.avoid_collisions)
        except Exception as exc:  # noqa: BLE001
            return self._failed("compute_ik", response, exc)
        response.error = conv.error_msg(None)
        response.solution = conv.joint_state_msg(self._robot.joint_names, q, self.get_clock().now().to_msg())
        return response

    def _ik_seed(self, msg: JointState) -> tuple[dict[str, float], bool]:
        """(seed values, whether every name must be a robot joint): the request's, else /joint_states."""
        if msg.name or msg.position:
            return conv.joint_state_values(msg, "seed_state"), True
        return self.latest_joint_state(), False

    def _on_apply_scene(self, request: ApplyScene.Request, response: ApplyScene.Response):
        try:
            response.obstacle_names = self._scene.apply(
                list(request.obstacles), clear=request.clear, frame=self.settings.planning_frame,
                attachments=self._attachments,
            )  # fmt: skip
        except Exception as exc:  # noqa: BLE001
            response.obstacle_names = [o["name"] for o in self._scene.snapshot()[0].get("obstacles", [])]
            return self._failed("apply_scene", response, exc, source="scene")
        response.error = conv.error_msg(None)
        self._publish_markers()
        return response

    # ------------------------------------------------------------ manipulation services (docs/manipulation.md)

    async def _on_compute_fk(self, request: ComputeFK.Request, response: ComputeFK.Response):
        try:
            values = self._start_state(request.robot_state)
            poses = await self._in_worker(manipulation.fk_in_context, values, list(request.links))
        except Exception as exc:  # noqa: BLE001 - every failure becomes an error code
            return self._failed("compute_fk", response, exc)
        response.error = conv.error_msg(None)
        manipulation.fill_fk(response, poses, self.settings.planning_frame, self.get_clock().now().to_msg())
        return response

    async def _on_check_state_validity(self, request: CheckStateValidity.Request, response):
        try:
            values = self._start_state(request.robot_state)
            constraints = manipulation.path_constraints(request.constraints, self.settings.planning_frame)
            answer = await self._in_worker(manipulation.validity_in_context, values, constraints)
        except Exception as exc:  # noqa: BLE001
            return self._failed("check_state_validity", response, exc)
        response.error = conv.error_msg(None)
        manipulation.fill_validity(response, answer)
        return response

    def _on_query_planners(self, _request: QueryPlanners.Request, response: QueryPlanners.Response):
        config = self.config
        manipulation.fill_planners(response, query_planners(config.planner_params), config.default_planner)
        return response

    async def _on_compute_cartesian_path(self, request: ComputeCartesianPath.Request, response):
        settings = self.settings
        try:
            start = self._start_state(request.start_state)
            cartesian = manipulation.cartesian_request(
                request, start, settings.default_group, settings.planning_frame, settings.max_planning_time
            )
            result = await self._in_worker(manipulation.cartesian_in_context, cartesian)
        except Exception as exc:  # noqa: BLE001
            return self._failed("compute_cartesian_path", response, exc)
        manipulation.fill_cartesian(response, result, settings.planning_frame, self.get_clock().now().to_msg())
        if not result.success:
            self._log_failure("compute_cartesian_path", response.error)
        return response

    def _failed(self, service: str, response: Any, exc: BaseException, source: str = "node") -> Any:
        """``response`` (or action result) with ``exc`` as its error, logged."""
        response.error = conv.error_msg(exc, source=source)
        self._log_failure(service, response.error)
        return response

    def _on_get_scene(self, _request: GetScene.Request, response: GetScene.Response):
        scene_dict, _ = self._scene.snapshot()
        frame = self.settings.planning_frame
        response.obstacles = [conv.obstacle_to_msg(o, frame) for o in scene_dict.get("obstacles", [])]
        response.scene_yaml = Scene.from_dict(scene_dict).to_yaml()
        return response

    def _log_failure(self, service: str, error: PlanningError) -> None:
        self.get_logger().warning(f"{service}: {conv.code_name(error.code)}: {error.message}")


def wait_for_robot_description(node: Node, timeout: float) -> str:
    """The URDF on ``node``'s latched ``robot_description`` topic (robot_state_publisher's), read by a helper node.

    The helper node (same context, not spun by any executor) keeps the wait off the node's executor,
    which may be running the configure transition that asks.
    """
    topic = node.resolve_topic_name("robot_description")
    reader = rclpy.create_node(
        f"{node.get_name()}_description_reader",
        namespace=node.get_namespace(),
        context=node.context,
        use_global_arguments=False,
        start_parameter_services=False,
        enable_rosout=False,
    )
    try:
        received, msg = wait_for_message(String, reader, topic, qos_profile=LATCHED, time_to_wait=timeout)
    finally:
        reader.destroy_node()
    if not received or not msg.data.strip():
        raise errors.InvalidParameter(
            f"robot_description_source is topic, but no URDF arrived on {topic} within {timeout} s "
            "(is robot_state_publisher running?)"
        )
    return msg.data


def _checked_config(build: Callable[[], PlannerConfig]) -> PlannerConfig:
    """``build()``; a value PlannerConfig refuses becomes InvalidParameter (naming it)."""
    try:
        return build()
    except ValueError as exc:
        raise errors.InvalidParameter(str(exc)) from None


def _check_group(robot: RobotModel, group: str) -> None:
    if group not in robot.groups:
        raise errors.InvalidParameter(
            f"parameter 'default_group' = {group!r} is not a group of the robot; known: {', '.join(robot.groups)}"
        )


def _scaling(value: float, field: str) -> float:
    """A request's scaling factor ``field``: 0 means 1.0, else checked as the core checks it."""
    return 1.0 if value == 0.0 else timing.check_scaling(value, field)


def _ik_timeout(value: float, settings: NodeSettings) -> float:
    """A ComputeIK request's budget: <= 0 is the node's ik_timeout; NaN, inf or past max_planning_time is refused."""
    if value <= 0.0:
        return settings.ik_timeout
    if not (math.isfinite(value) and value <= settings.max_planning_time):
        raise errors.InvalidRequest(
            f"timeout must be finite and <= max_planning_time {settings.max_planning_time} s (<= 0: ik_timeout), "
            f"got {value:.3g}"
        )
    return float(value)


def _time_left(deadline: float, budget_name: str) -> float:
    """Seconds to ``deadline``; PlanningTimedOut if the request used its budget waiting for a worker."""
    left = deadline - time.monotonic()
    if left <= 0.0:
        raise errors.PlanningTimedOut(f"the {budget_name} ran out while the request waited for a worker", source="node")
    return left


def _plan_in_context(
    context: PlanningContext, motion_request: MotionRequest, deadline: float, monitor: PlanMonitor | None
):
    budget = _time_left(deadline, "allowed_planning_time")
    planner = context.processes or context.planner
    return planner.plan(dataclasses.replace(motion_request, time_budget=budget), monitor)


def _feedback_msg(progress: Progress) -> PlanMotionAction.Feedback:
    return PlanMotionAction.Feedback(
        stage=progress.stage,
        elapsed=float(progress.elapsed),
        nodes=int(progress.info.get("nodes", 0)),
        best_cost=float(progress.info.get("best_cost", math.nan)),
    )


def _ik_in_context(context: PlanningContext, group, targets, seed, strict, deadline, avoid_collisions) -> np.ndarray:
    _time_left(deadline, "IK timeout")
    robot = context.planner.robot  # with the attached objects (their checker checks them)
    q_seed = conv.configuration(robot, seed, strict=strict)
    is_valid = context.planner.checker.is_valid if avoid_collisions else None
    return solve_ik(robot, targets, q_seed, group, deadline=deadline, is_valid=is_valid)


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
