"""arm_sim_node: a simulated arm (MuJoCo, 1 kHz) that executes joint trajectories like ros2_control would.

- publishes ``joint_states`` (sensor_msgs/JointState: positions, velocities, actuator efforts) at
  ``joint_state_rate`` (250 Hz) while active;
- offers ``execute_trajectory`` (maru_planner_interfaces/action/ExecuteTrajectory, shaped like
  control_msgs/FollowJointTrajectory): joint_trajectory_controller's interpolation and tolerances
  (:mod:`maru_planner.execution`), feedback (desired, actual, error) at ``feedback_rate`` (25 Hz), result
  codes SUCCESSFUL, INVALID_GOAL (bad points, a first point farther than ``start_tolerance`` from the arm),
  INVALID_JOINTS, OLD_HEADER_TIMESTAMP, PATH/GOAL_TOLERANCE_VIOLATED, and how the arm followed (tracking
  error, overrun, contacts with obstacles, torque saturation). A new goal preempts the running one (which
  ends ABORTED, INVALID_GOAL, "preempted by a new goal"); a cancel brings the arm to rest within its
  acceleration limits (the goal ends CANCELED).
- offers the same executor as ``follow_joint_trajectory`` (control_msgs/action/FollowJointTrajectory, the action a
  real robot's joint_trajectory_controller serves; parameter ``follow_joint_trajectory_action``, '' = not served):
  the same tolerances, codes, preemption and cancel, control_msgs' result and feedback
  (:mod:`maru_planner.ros.follow_joint_trajectory`). Without control_msgs installed only ``execute_trajectory``
  is served (one log line).

Parameters: :class:`ArmSimConfig` (``config/arm_sim.yaml``) and two pairs of arrays (:data:`ARRAY_PARAMETERS`):
``initial_joint_names`` + ``initial_positions`` (rad or m; these joints start there instead of at
``initial_state``'s values) and ``payload_names`` + ``payload_masses`` (kg of attached objects of the scene,
uniform density; others weigh nothing). The robot, scene, start state, payloads and servo gains are read at
configure; tolerances and rates at every goal. Physics runs on its own thread at ``real_time_factor``
while the node is active (deactivating cancels a running goal and pauses the arm; a signal stops it before the
publisher goes).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import threading
import time
from typing import Any

import numpy as np
from builtin_interfaces.msg import Duration
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.exceptions import ParameterUninitializedException
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from maru_planner.errors import InvalidJointNames, InvalidRequest, MaruError
from maru_planner.execution.executor import ArmController, ExecutionResult
from maru_planner.execution.interpolation import TrajectoryPoints, checked_points
from maru_planner.execution.tolerances import ResultCode, Tolerances, tolerances
from maru_planner.params import dataclass_params, param
from maru_planner.physics.arm_model import ServoGains, build_arm_model
from maru_planner.physics.arm_sim import ArmSim
from maru_planner.robot import RobotModel
from maru_planner.robot.robot_profile import PROFILES
from maru_planner.ros import parameters
from maru_planner.ros.follow_joint_trajectory import (
    ActionShape,
    ExecuteTrajectoryShape,
    FollowJointTrajectoryShape,
    follow_joint_trajectory_type,
)
from maru_planner.ros.lifecycle import ManagedNode, run_node
from maru_planner.scene import Scene
from maru_planner_interfaces.action import ExecuteTrajectory

R = ExecuteTrajectory.Result


@dataclasses.dataclass
class ArmSimConfig:
    """arm_sim_node's parameters."""

    robot: str = param("maru1", "robot profile (maru_planner.robot profiles)", read_only=True)
    scene_file: str = param("", "scene YAML whose obstacles become MuJoCo geoms ('' = none)", read_only=True)
    initial_state: str = param(
        "home", "start state: a named state of the robot's SRDF ('neutral' or a name it lacks: the neutral one)",
        read_only=True,
    )  # fmt: skip
    saturation_error: float = param(0.02, "servo: kp = effort limit / this (rad)", lower=1e-4, upper=1.0,
                                    read_only=True)  # fmt: skip
    damping_ratio: float = param(1.0, "servo damping ratio (kv from each joint's inertia)", lower=0.05, upper=5.0,
                                 read_only=True)  # fmt: skip
    gravity_compensation: bool = param(True, "servo adds the links' gravity torques (within the effort limits)",
                                       read_only=True)  # fmt: skip
    acceleration_feedforward: bool = param(
        True, "servo adds M(q) x the desired accelerations (false: feedback only)", read_only=True
    )
    joint_state_rate: float = param(250.0, "joint_states rate (Hz)", lower=1.0, upper=1000.0, read_only=True)
    feedback_rate: float = param(25.0, "execute_trajectory feedback rate (Hz)", lower=1.0, upper=250.0)
    real_time_factor: float = param(1.0, "simulated seconds per wall-clock second", lower=0.01, upper=100.0)
    path_tolerance: float = param(0.05, "default path position tolerance (rad; 0 = not checked)", lower=0.0)
    goal_tolerance: float = param(0.01, "default goal position tolerance (rad)", lower=0.0)
    goal_velocity_tolerance: float = param(0.01, "default goal velocity tolerance (rad/s)", lower=0.0)
    start_tolerance: float = param(0.01, "largest distance of the first point from the arm (rad; 0 = any)", lower=0.0)
    follow_joint_trajectory_action: str = param(
        "follow_joint_trajectory", "name of the control_msgs FollowJointTrajectory server ('' = none)", read_only=True
    )


SPECS = dataclass_params(ArmSimConfig)
STRING_ARRAY, DOUBLE_ARRAY = Parameter.Type.STRING_ARRAY, Parameter.Type.DOUBLE_ARRAY
ARRAY_PARAMETERS: tuple[tuple[str, Parameter.Type, str], ...] = (
    ("initial_joint_names", STRING_ARRAY, "joints that start at initial_positions instead of initial_state's"),
    ("initial_positions", DOUBLE_ARRAY, "start values (rad or m, within the joint limits) of initial_joint_names"),
    ("payload_names", STRING_ARRAY, "attached objects of the scene that have a mass"),
    ("payload_masses", DOUBLE_ARRAY, "their masses (kg, > 0), in the order of payload_names"),
)
ERROR_CODES: tuple[tuple[type[MaruError], int], ...] = (
    (InvalidJointNames, R.INVALID_JOINTS),
    (MaruError, R.INVALID_GOAL),
)


class _Goal:
    """An accepted goal: its handle, and the result the physics thread (or a preemption) leaves."""

    def __init__(self, handle: Any):
        self.handle = handle
        self.done = threading.Event()
        self.result: ExecutionResult | None = None
        self.preempted = False

    def finish(self, result: ExecutionResult, *, preempted: bool = False) -> None:
        self.result, self.preempted = result, preempted
        self.done.set()


class ArmSimNode(ManagedNode):
    def __init__(self, **kwargs: Any):
        super().__init__("arm_sim_node", **kwargs)
        self.config = ArmSimConfig(**parameters.declare_parameters(self, SPECS))
        for name, kind, description in ARRAY_PARAMETERS:
            self.declare_parameter(name, kind, ParameterDescriptor(description=description, read_only=True))
        parameters.add_on_set_parameters_callback(self, SPECS, self._apply)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._goal: _Goal | None = None
        self.start()

    def _apply(self, changes: dict[str, Any]) -> None:
        self.config = dataclasses.replace(self.config, **changes)

    # ------------------------------------------------------------------------------------------ lifecycle --
    def configure(self) -> None:
        config = self.config
        if config.robot not in PROFILES:
            raise InvalidRequest(f"parameter 'robot': unknown robot {config.robot!r} (have {sorted(PROFILES)})")
        robot = RobotModel.from_profile(config.robot)
        scene = Scene.from_yaml(config.scene_file) if config.scene_file else None
        q0 = self._initial_state(robot)
        gains = ServoGains(
            config.saturation_error,
            config.damping_ratio,
            gravity_compensation=config.gravity_compensation,
            acceleration_feedforward=config.acceleration_feedforward,
        )
        payloads = paired(self._array("payload_names"), self._array("payload_masses"), "payload")
        for name, mass in payloads.items():
            if not (math.isfinite(mass) and mass > 0.0):
                raise InvalidRequest(
                    f"parameter 'payload_masses': {name!r} must weigh a finite mass > 0 kg, got {mass}"
                )
        sim = ArmSim(build_arm_model(robot, scene, gains, q0=q0, payloads=payloads))
        sim.reset(q0)
        self.controller = ArmController(sim)
        self.joint_states = self.create_lifecycle_publisher(JointState, "joint_states", 10)
        group = ReentrantCallbackGroup()
        self._serve("execute_trajectory", ExecuteTrajectoryShape(), group)
        if config.follow_joint_trajectory_action:
            kind = follow_joint_trajectory_type()
            if kind is None:
                self.get_logger().warn(
                    "control_msgs is not installed: no FollowJointTrajectory server (execute_trajectory only)"
                )
            else:
                self._serve(config.follow_joint_trajectory_action, FollowJointTrajectoryShape(kind), group)
        self.get_logger().info(
            f"{robot.name}: {robot.nq} joints, {len(scene.obstacles) if scene else 0} obstacles, "
            f"kp {sorted(set(sim.arm.kp.round(0).tolist()))} N m/rad"
        )

    def _serve(self, name: str, shape: ActionShape, group: ReentrantCallbackGroup) -> None:
        ActionServer(
            self, shape.kind, name, lambda handle: self._execute(handle, shape), goal_callback=self.goal_when_active,
            cancel_callback=lambda _goal: CancelResponse.ACCEPT, callback_group=group,
        )  # fmt: skip

    def _initial_state(self, robot: RobotModel) -> np.ndarray:
        name = self.config.initial_state
        if name in robot.named_states:
            q = np.array(robot.named_state(name), dtype=float)
        else:
            if name != "neutral":
                self.get_logger().warn(f"initial_state {name!r}: not a named state of {robot.name}; starting neutral")
            q = np.array(robot.neutral(), dtype=float)
        given = paired(self._array("initial_joint_names"), self._array("initial_positions"), "initial")
        for joint, value in given.items():
            if joint not in robot.joint_names:
                raise InvalidRequest(f"parameter 'initial_joint_names': {robot.name} has no joint {joint!r}")
            i = robot.joint_names.index(joint)
            lo, hi = robot.lower_limits[i], robot.upper_limits[i]
            if not (math.isfinite(value) and lo <= value <= hi):
                raise InvalidRequest(
                    f"parameter 'initial_positions': {joint} = {value} is outside [{lo:.4g}, {hi:.4g}]"
                )
            q[i] = value
        return q

    def _array(self, name: str) -> list[Any]:
        """An array parameter's values; not given (declared by type, with no value): none."""
        try:
            value = self.get_parameter(name).value
        except ParameterUninitializedException:
            return []
        return list(value) if value is not None else []

    def activate(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._physics, name="arm_sim_physics", daemon=True)
        self._thread.start()

    def deactivate(self) -> None:
        with self._lock:
            result = self.controller.cancel()
            if result is not None and self._goal is not None:
                self._goal.finish(result)
                self._goal = None
        self._stop_physics()

    def cleanup(self) -> None:
        # after a signal there is no deactivate: the thread must not publish on a publisher being destroyed
        self._stop_physics()

    def _stop_physics(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._thread = None

    # -------------------------------------------------------------------------------------------- physics --
    def _physics(self) -> None:
        """Step the arm in real time (scaled), ``joint_state_rate`` ticks a second, publishing each tick."""
        sim = self.controller.sim
        tick = 1.0 / self.config.joint_state_rate
        steps = max(1, round(tick / sim.timestep))
        next_time = time.monotonic()
        while not self._stop.is_set():
            with self._lock:
                for _ in range(steps):
                    result = self.controller.step()
                    if result is not None and self._goal is not None:
                        self._goal.finish(result)
                        self._goal = None
                state = sim.state()
            if not self._publish_state(state.positions, state.velocities, state.efforts):
                return
            next_time += steps * sim.timestep / self.config.real_time_factor
            delay = next_time - time.monotonic()
            if delay > 0:
                self._stop.wait(delay)
            elif delay < -0.1:  # fell behind (a slow machine): do not try to catch up
                next_time = time.monotonic()

    def _publish_state(self, positions: np.ndarray, velocities: np.ndarray, efforts: np.ndarray) -> bool:
        """Publish one joint state; False when a signal shut the context down meanwhile (the node is exiting)."""
        msg = JointState()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.name = list(self.controller.sim.arm.joint_names)
        msg.position, msg.velocity, msg.effort = positions.tolist(), velocities.tolist(), efforts.tolist()
        try:
            self.joint_states.publish(msg)
        except Exception:  # rcl's RCLError "context is invalid", rclpy's InvalidHandle
            if self._stop.is_set() or not self.context.ok():
                return False
            raise
        return True

    # --------------------------------------------------------------------------------------------- action --
    def _execute(self, handle: Any, shape: ActionShape) -> Any:
        request = handle.request
        try:
            shape.check(request)
            points = points_from_msg(request.trajectory)
            tol = self._tolerances(request, points)
            self._wait_for_start(handle, request.trajectory, points)
        except _OldHeader as exc:
            return _refuse(handle, shape.refused(R.OLD_HEADER_TIMESTAMP, str(exc)))
        except MaruError as exc:
            return _refuse(handle, shape.refused(_code_of(exc), str(exc)))
        goal = _Goal(handle)
        with self._lock:
            try:
                self.controller.start(points, tol)
            except MaruError as exc:
                return _refuse(handle, shape.refused(_code_of(exc), str(exc)))
            previous, self._goal = self._goal, goal
            if previous is not None and self.controller.preempted is not None:
                previous.finish(self.controller.preempted, preempted=True)
        period = 1.0 / self.config.feedback_rate
        while not goal.done.wait(period):
            if handle.is_cancel_requested:
                with self._lock:
                    if self._goal is goal:
                        result = self.controller.cancel()
                        assert result is not None
                        goal.finish(result)
                        self._goal = None
                break
            self._feedback(handle, shape)
        goal.done.wait()
        assert goal.result is not None
        return _finish(handle, shape, goal.result, goal.preempted)

    def _feedback(self, handle: Any, shape: ActionShape) -> None:
        with self._lock:
            sample = self.controller.latest_sample()
        if sample is None:
            return
        _, names, desired, actual = sample
        handle.publish_feedback(shape.feedback(self.get_clock().now().to_msg(), list(names), desired, actual))

    def _tolerances(self, request: Any, points: TrajectoryPoints) -> Tolerances:
        c, names = self.config, points.joint_names
        goal_time = _seconds(request.goal_time_tolerance)
        return tolerances(
            len(names), points.duration,
            path_position=_per_joint(request.path_tolerance, names, "position", c.path_tolerance),
            path_velocity=_per_joint(request.path_tolerance, names, "velocity", 0.0),
            goal_position=_per_joint(request.goal_tolerance, names, "position", c.goal_tolerance),
            goal_velocity=_per_joint(request.goal_tolerance, names, "velocity", c.goal_velocity_tolerance),
            goal_time=goal_time if goal_time > 0 else None, start=c.start_tolerance,
        )  # fmt: skip

    def _wait_for_start(self, handle: Any, msg: JointTrajectory, points: TrajectoryPoints) -> None:
        """Until ``header.stamp`` (zero: now); _OldHeader when the trajectory would already be over."""
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        if stamp == 0.0:
            return
        now = self.get_clock().now().nanoseconds * 1e-9
        if stamp + points.duration < now:
            raise _OldHeader(f"trajectory ended {now - stamp - points.duration:.3f} s ago (header.stamp in the past)")
        while stamp > self.get_clock().now().nanoseconds * 1e-9 and not handle.is_cancel_requested:
            time.sleep(0.001)


class _OldHeader(Exception):
    pass


def paired(names: list[str], values: list[float], prefix: str) -> dict[str, float]:
    """``names`` -> ``values`` of the parameter pair ``<prefix>_names``/``..._positions|masses``
    (InvalidRequest if their lengths differ or a name repeats)."""
    if len(names) != len(values):
        raise InvalidRequest(f"parameters '{prefix}_*': {len(names)} names but {len(values)} values")
    if len(set(names)) != len(names):
        raise InvalidRequest(f"parameters '{prefix}_*': a name is given twice in {names}")
    return dict(zip(names, (float(v) for v in values), strict=True))


def points_from_msg(msg: JointTrajectory) -> TrajectoryPoints:
    """trajectory_msgs/JointTrajectory as checked points (velocities/accelerations absent on a point: NaN rows)."""
    names, k = list(msg.joint_names), len(msg.joint_names)
    if not msg.points:
        raise InvalidRequest("trajectory has no points")

    def rows(field: str) -> np.ndarray | None:
        values = [list(getattr(p, field)) for p in msg.points]
        if not any(values):
            return None
        for i, row in enumerate(values):
            if row and len(row) != k:
                raise InvalidRequest(f"trajectory point {i}: {len(row)} {field} for {k} joints")
        return np.array([row if row else [math.nan] * k for row in values], dtype=float)

    positions = [list(p.positions) for p in msg.points]
    for i, row in enumerate(positions):
        if len(row) != k:
            raise InvalidRequest(f"trajectory point {i}: {len(row)} positions for {k} joints")
    times = [_seconds(p.time_from_start) for p in msg.points]
    return checked_points(names, times, positions, rows("velocities"), rows("accelerations"))


def _per_joint(entries: Any, names: list[str], field: str, default: float) -> np.ndarray:
    """control_msgs' JointTolerance semantics: > 0 the bound, 0 the default, < 0 unchecked (our 0)."""
    values = np.full(len(names), default, dtype=float)
    index = {n: i for i, n in enumerate(names)}
    for entry in entries:
        if entry.name not in index:
            raise InvalidJointNames(f"tolerance for joint '{entry.name}', which the trajectory does not move")
        value = float(getattr(entry, field))
        if not math.isfinite(value):
            raise InvalidRequest(f"tolerance of joint '{entry.name}': {field} is not a number")
        if value != 0.0:
            values[index[entry.name]] = value if value > 0 else 0.0
    return values


def _seconds(duration: Duration) -> float:
    return duration.sec + 1e-9 * duration.nanosec


def _code_of(exc: MaruError) -> int:
    return next(code for kind, code in ERROR_CODES if isinstance(exc, kind))


def _refuse(handle: Any, result: Any) -> Any:
    handle.abort()
    return result


def _finish(handle: Any, shape: ActionShape, result: ExecutionResult, preempted: bool) -> Any:
    code = int(ResultCode.INVALID_GOAL if preempted else result.code)
    msg = shape.finished(code, result.message, result)
    if result.cancelled and not preempted and handle.is_cancel_requested:
        handle.canceled()
    elif result.success:
        handle.succeed()
    else:
        handle.abort()
    return msg


def main(args: list[str] | None = None) -> int:
    return run_node("arm_sim_node", ArmSimNode, args, executor_threads=lambda _node: 4)


if __name__ == "__main__":
    sys.exit(main())
