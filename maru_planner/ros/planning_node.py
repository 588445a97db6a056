"""``planning_node``: ROS 2 services around the arm-planning core.

A thin adapter: messages are converted in :mod:`planning_conversions`, the
work is done by the core (``MotionPlanner``, ``solve_ik``, ``Scene``).

Concurrency: service callbacks are coroutines. They hand the core call to a
small pool of worker threads, each owning its own robot model, collision
checker and planner (pinocchio data and OMPL set-ups are not shared between
threads), and ``await`` the answer. No executor thread is held while a plan
runs, so ``/joint_states``, scene updates and other requests keep being
served, and every request gets its own answer.
"""

from __future__ import annotations

import copy
import math
import queue
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from maru_planner import errors
from maru_planner.paths import config_path, urdf_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig
from maru_planner.robot import RobotModel
from maru_planner.robot.ik import solve_ik
from maru_planner.ros import planning_conversions as conv
from maru_planner.ros.env import configure_loopback_dds
from maru_planner.ros.markers import plan_markers, scene_markers
from maru_planner.scene import Obstacle, Scene
from maru_planner_interfaces.msg import PlanningError, SceneObstacle
from maru_planner_interfaces.srv import ApplyScene, ComputeIK, GetScene, PlanMotion

NODE_NAME = "planning_node"
DEFAULT_URDF = "maru1_upper_body.urdf"
DEFAULT_SRDF = "maru1_upper_body.srdf"
DEFAULT_SCENE = "scenes/maru13_desk_box.yaml"

LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)

PARAMETERS = {
    "robot_urdf": "",  # empty = the package's urdf/maru1_upper_body.urdf
    "robot_srdf": "",  # empty = the package's urdf/maru1_upper_body.srdf
    "package_dirs": [""],  # extra mesh search dirs (package:// URIs); [""] = none
    "planning_frame": "base_link",
    "default_group": "upper_body",
    "default_planner": "RRTConnect",
    "resolution": 0.02,  # rad: collision-check step along an edge
    "collision_model": "exact",  # "exact" (coal) or "spheres" (fast; paths verified on the exact model)
    "max_planning_time": 60.0,  # s: larger allowed_planning_time is answered INVALID_REQUEST
    "default_attempts": 1,
    "ik_timeout": 1.0,  # s: ComputeIK budget when the request gives none
    "scene_file": "",  # empty = config/scenes/maru13_desk_box.yaml; "none" = empty scene; relative: cwd, then config/
    "workers": 2,  # planning contexts (threads); more requests queue
    "executor_threads": 4,
    "marker_period": 1.0,  # s: markers are re-sent to new subscribers at this period
}


class PlanningContext:
    """Everything one worker thread needs to plan: its own robot, checker and planner."""

    def __init__(self, robot, checker, planner):
        self.robot = robot
        self.checker = checker
        self.planner = planner
        self.scene_version = -1


class SceneStore:
    """The node's planning scene, changed atomically; readers get copies."""

    def __init__(self, scene_dict: dict):
        self._lock = threading.Lock()
        self._scene = Scene.from_dict(scene_dict)
        self.version = 0

    def snapshot(self) -> tuple[dict, int]:
        with self._lock:
            return copy.deepcopy(self._scene.to_dict()), self.version

    def scene(self):
        scene_dict, _ = self.snapshot()
        return Scene.from_dict(scene_dict)

    def apply(self, obstacles: list[SceneObstacle], clear: bool, frame: str) -> list[str]:
        """Apply ADD/MOVE/REMOVE operations (after an optional clear) all-or-nothing; return the names.

        Obstacle poses must be in ``frame`` (the planning frame) or have an empty frame_id.
        """
        with self._lock:
            scene = Scene.from_dict(copy.deepcopy(self._scene.to_dict()))
            if clear:
                scene.clear()
            for msg in obstacles:
                _apply_obstacle(scene, msg, frame)
            self._scene = scene
            self.version += 1
            return [o["name"] for o in scene.to_dict().get("obstacles", [])]


def _apply_obstacle(scene, msg: SceneObstacle, frame: str) -> None:
    """One ADD/MOVE/REMOVE on ``scene`` (raises InvalidScene naming the obstacle)."""
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
    else:
        raise errors.InvalidScene(f"obstacle '{msg.name}': operation {msg.operation} is not ADD, MOVE or REMOVE")


class PlanningNode(Node):
    """Plan, IK and scene services for the upper-body arm planner."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        for name, default in PARAMETERS.items():
            self.declare_parameter(name, default)
        self._latest_joints: dict[str, float] = {}
        self._joints_lock = threading.Lock()
        self._last_plan_markers = None
        self._marker_lock = threading.Lock()  # plan_markers uses self._robot's shared pinocchio data
        self._marker_subscribers = 0

        self._scene = SceneStore(self._load_scene_dict())
        self._contexts: queue.SimpleQueue[PlanningContext] = queue.SimpleQueue()
        n_workers = max(1, self._param("workers"))
        for _ in range(n_workers):
            self._contexts.put(self._make_context())
        self._robot = self._make_robot()  # read-only use in the executor threads (names, markers)
        self._workers = ThreadPoolExecutor(max_workers=n_workers, thread_name_prefix="planner")
        self._make_interfaces()
        self.get_logger().info(
            f"ready: robot {len(self._robot.joint_names)} joints, groups {sorted(self._robot.groups)}, "
            f"scene {len(self._scene.snapshot()[0].get('obstacles', []))} obstacles, {n_workers} workers"
        )

    # ------------------------------------------------------------ set-up

    def _param(self, name: str):
        return self.get_parameter(name).value

    def _robot_files(self) -> tuple[str, str, list[str]]:
        urdf = self._param("robot_urdf") or str(urdf_path(DEFAULT_URDF))
        srdf = self._param("robot_srdf") or str(urdf_path(DEFAULT_SRDF))
        package_dirs = [d for d in self._param("package_dirs") if d]
        return urdf, srdf, package_dirs

    def _make_robot(self):
        urdf, srdf, package_dirs = self._robot_files()
        return RobotModel.from_urdf(urdf, srdf, package_dirs=package_dirs or None)

    def _make_context(self) -> PlanningContext:
        robot = self._make_robot()
        config = PlannerConfig(
            resolution=self._param("resolution"),
            default_planner=self._param("default_planner"),
            collision_model=self._param("collision_model"),
        )
        planner = MotionPlanner.from_scene(robot, self._scene.scene(), config)
        return PlanningContext(robot, planner.checker, planner)

    def _load_scene_dict(self) -> dict:
        scene_file = self._param("scene_file")
        if scene_file.lower() == "none":
            return Scene().to_dict()
        path = Path(scene_file) if scene_file else config_path(DEFAULT_SCENE)
        if not path.is_absolute() and not path.is_file():
            path = config_path(scene_file)  # e.g. "scenes/maru6_desk.yaml" from the package's config/
        return Scene.from_yaml(path).to_dict()

    def _make_interfaces(self) -> None:
        services = ReentrantCallbackGroup()
        self.create_service(PlanMotion, "plan_motion", self._on_plan_motion, callback_group=services)
        self.create_service(ComputeIK, "compute_ik", self._on_compute_ik, callback_group=services)
        self.create_service(ApplyScene, "apply_scene", self._on_apply_scene, callback_group=services)
        self.create_service(GetScene, "get_scene", self._on_get_scene, callback_group=services)
        self.create_subscription(
            JointState, "/joint_states", self._on_joint_states, 50, callback_group=MutuallyExclusiveCallbackGroup()
        )
        self.create_subscription(
            SceneObstacle,
            "/planning_scene_obstacles",
            self._on_scene_obstacle,
            50,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )
        self._trajectory_pub = self.create_publisher(JointTrajectory, "~/planned_trajectory", LATCHED)
        self._marker_pub = self.create_publisher(MarkerArray, "~/markers", 10)
        description = self.create_publisher(String, "robot_description", LATCHED)
        description.publish(String(data=Path(self._robot_files()[0]).read_text()))
        self._description_pub = description
        self.create_timer(
            self._param("marker_period"), self._on_marker_timer, callback_group=MutuallyExclusiveCallbackGroup()
        )

    # ------------------------------------------------------------ worker pool

    def _in_worker(self, fn, *args) -> Future:
        """Run ``fn(context, *args)`` on a planning worker; an rclpy Future a coroutine can await."""
        future = Future(executor=self.executor)

        def run():
            context = self._contexts.get()
            try:
                self._sync_scene(context)
                future.set_result(fn(context, *args))
            except BaseException as exc:  # noqa: BLE001 - handed to the awaiting callback
                future.set_exception(exc)
            finally:
                self._contexts.put(context)
                if self.executor is not None:
                    self.executor.wake()

        self._workers.submit(run)
        return future

    def _sync_scene(self, context: PlanningContext) -> None:
        if context.scene_version == self._scene.version:
            return
        scene_dict, version = self._scene.snapshot()
        if context.scene_version != version:
            context.planner.set_scene(Scene.from_dict(scene_dict))
            context.scene_version = version

    # ------------------------------------------------------------ topics

    def _on_joint_states(self, msg: JointState) -> None:
        try:
            values = conv.joint_state_values(msg, "/joint_states")
        except errors.MaruError as exc:
            self.get_logger().warning(f"ignoring /joint_states: {exc}", throttle_duration_sec=5.0)
            return
        with self._joints_lock:
            self._latest_joints.update(values)

    def latest_joint_state(self) -> dict[str, float]:
        with self._joints_lock:
            return dict(self._latest_joints)

    def _on_scene_obstacle(self, msg: SceneObstacle) -> None:
        try:
            self._scene.apply([msg], clear=False, frame=self._param("planning_frame"))
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
        frame = self._param("planning_frame")
        markers = scene_markers(self._scene.snapshot()[0], frame, self.get_clock().now().to_msg())
        with self._marker_lock:
            if self._last_plan_markers is not None:
                markers.markers.extend(self._last_plan_markers.markers)
        self._marker_pub.publish(markers)

    # ------------------------------------------------------------ services

    async def _on_plan_motion(self, request: PlanMotion.Request, response: PlanMotion.Response):
        started = time.perf_counter()
        try:
            motion_request = self._motion_request(request)
            result = await self._in_worker(_plan_in_context, motion_request)
        except Exception as exc:  # noqa: BLE001 - every failure becomes an error code
            response.error = conv.error_msg(exc, source="node")
            self._log_failure("plan_motion", response.error)
            return response
        response.error = conv.result_error_msg(result)
        response.planning_time = float(getattr(result.stats, "total_time", 0.0) or 0.0)
        response.stats = conv.stats_msg(result.stats)
        if not result.success:
            self._log_failure("plan_motion", response.error)
            return response
        stamp = self.get_clock().now().to_msg()
        response.trajectory = conv.trajectory_msg(result.trajectory, self._param("planning_frame"), stamp)
        # publishing (and marker FK) happens after the answer has gone out
        self.executor.create_task(self._publish_plan, response.trajectory, result.trajectory, motion_request.start)
        self.get_logger().info(
            f"plan_motion {request.group or self._param('default_group')} "
            f"{response.stats.planner_id}: {len(response.trajectory.points)} points, "
            f"core {response.planning_time:.3f} s, in node {time.perf_counter() - started:.3f} s"
        )
        return response

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

    def _motion_request(self, request: PlanMotion.Request):
        """Core ``MotionRequest`` of a ``PlanMotion`` request (raises typed errors for bad fields)."""
        budget = float(request.allowed_planning_time)
        if not math.isfinite(budget) or budget <= 0.0:
            raise errors.InvalidRequest(f"allowed_planning_time must be > 0 s, got {budget}")
        if budget > self._param("max_planning_time"):
            raise errors.InvalidRequest(
                f"allowed_planning_time {budget} s exceeds max_planning_time {self._param('max_planning_time')} s"
            )
        start = self._start_state(request.start_state)
        goal_joints = None
        if request.goal_joint_names or request.goal_positions:
            goal_joints = conv.named_values(request.goal_joint_names, request.goal_positions, "goal")
        goal_poses = None
        if request.goal_poses or request.goal_links:
            goal_poses = conv.pose_goals(request.goal_poses, request.goal_links, self._param("planning_frame"))
        if goal_joints is None and goal_poses is None:
            raise errors.InvalidRequest("no goal: give goal_joint_names + goal_positions or goal_poses + goal_links")
        if goal_joints is not None and goal_poses is not None:
            raise errors.InvalidRequest("give either a joint goal or pose goals, not both")
        return MotionRequest(
            group=request.group or self._param("default_group"),
            start=start,
            goal_joints=goal_joints,
            goal_poses=goal_poses,
            planner_id=request.planner_id or self._param("default_planner"),
            time_budget=budget,
            seed=None if request.seed < 0 else int(request.seed),
            attempts=int(request.num_attempts) if request.num_attempts > 0 else self._param("default_attempts"),
            velocity_scaling=_scaling(request.max_velocity_scaling_factor, "max_velocity_scaling_factor"),
            acceleration_scaling=_scaling(request.max_acceleration_scaling_factor, "max_acceleration_scaling_factor"),
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
            targets = conv.pose_goals(request.poses, request.links, self._param("planning_frame"))
            if not targets:
                raise errors.InvalidRequest("no poses: give poses + links")
            seed, strict = self._ik_seed(request.seed_state)
            timeout = request.timeout if request.timeout > 0 else self._param("ik_timeout")
            group = request.group or self._param("default_group")
            q = await self._in_worker(_ik_in_context, group, targets, seed, strict, timeout, request.avoid_collisions)
        except Exception as exc:  # noqa: BLE001
            response.error = conv.error_msg(exc, source="node")
            self._log_failure("compute_ik", response.error)
            return response
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
                list(request.obstacles), clear=request.clear, frame=self._param("planning_frame")
            )
        except Exception as exc:  # noqa: BLE001
            response.error = conv.error_msg(exc, source="scene")
            response.obstacle_names = [o["name"] for o in self._scene.snapshot()[0].get("obstacles", [])]
            self._log_failure("apply_scene", response.error)
            return response
        response.error = conv.error_msg(None)
        self._publish_markers()
        return response

    def _on_get_scene(self, _request: GetScene.Request, response: GetScene.Response):
        scene_dict, _ = self._scene.snapshot()
        frame = self._param("planning_frame")
        response.obstacles = [conv.obstacle_to_msg(o, frame) for o in scene_dict.get("obstacles", [])]
        response.scene_yaml = Scene.from_dict(scene_dict).to_yaml()
        return response

    def _log_failure(self, service: str, error: PlanningError) -> None:
        self.get_logger().warning(f"{service}: {conv.code_name(error.code)}: {error.message}")

    def destroy_node(self):
        self._workers.shutdown(wait=False, cancel_futures=True)
        return super().destroy_node()


def _scaling(value: float, field: str) -> float:
    if value == 0.0:
        return 1.0
    if not (math.isfinite(value) and 0.0 < value <= 1.0):
        raise errors.InvalidRequest(f"{field} must be in (0, 1] (0 = 1.0), got {value}")
    return float(value)


def _plan_in_context(context: PlanningContext, motion_request):
    return context.planner.plan(motion_request)


def _ik_in_context(context: PlanningContext, group, targets, seed, strict, timeout, avoid_collisions) -> np.ndarray:
    robot = context.robot
    q_seed = conv.configuration(robot, seed, strict=strict)
    is_valid = context.checker.is_valid if avoid_collisions else None
    return solve_ik(robot, targets, q_seed, group, deadline=time.monotonic() + timeout, is_valid=is_valid)


class BackgroundPlanningNode:
    """``planning_node`` spun by its own executor in a daemon thread of this process.

    For demos and scripts that want the node without a subprocess; rclpy must already be
    initialised (after ``configure_loopback_dds()``). Keyword arguments override parameters::

        with BackgroundPlanningNode(default_planner="PRM", scene_file="none") as planning:
            ...  # call its services, e.g. with maru_planner.ros.planning_client.PlanningClient
    """

    def __init__(self, namespace: str = "", **parameters):
        from rclpy.parameter import Parameter

        overrides = [Parameter(name, value=value) for name, value in parameters.items()]
        self.node = PlanningNode(namespace=namespace, parameter_overrides=overrides)
        threads = max(2, self.node.get_parameter("executor_threads").value)
        self.executor = MultiThreadedExecutor(num_threads=threads)
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


def main(args=None) -> None:
    """Entry point of ``ros2 run maru_planner planning_node`` (and ``python -m``)."""
    configure_loopback_dds()
    rclpy.init(args=args)
    node = None
    try:
        node = PlanningNode()
        executor = MultiThreadedExecutor(num_threads=max(2, node.get_parameter("executor_threads").value))
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        if rclpy.ok():
            rclpy.try_shutdown()


if __name__ == "__main__":
    main()
