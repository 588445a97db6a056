"""Message <-> core conversions for the planning node.

Everything that turns a ROS message into a plain Python/numpy value for the
core (and back) lives here, and so does the ONE table mapping the core's
``PlanStatus`` values to ``PlanningError`` codes (typed exceptions map to a status in the core).
Joint values are always matched by name, never by position in an array.
"""

from __future__ import annotations

import array
import math

import numpy as np
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Pose
from sensor_msgs.msg import JointState
from shape_msgs.msg import SolidPrimitive
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from maru_planner import errors
from maru_planner.planning.types import known_status_of_error
from maru_planner.runtime.robot_state import configuration  # noqa: F401  (moved to the runtime; re-exported)
from maru_planner.scene import pose_matrix, shapes
from maru_planner_interfaces.msg import PlannerStats, PlanningError, SceneObstacle

# PlanStatus member name -> code: the one table from the core's statuses to PlanningError codes
# (typed errors reach it through the core's own error -> status table, planning.types).
STATUS_CODES: dict[str, int] = {
    "SUCCESS": PlanningError.SUCCESS,
    "PLANNING_FAILED": PlanningError.PLANNING_FAILED,
    "TIMED_OUT": PlanningError.TIMED_OUT,
    "INVALID_GROUP": PlanningError.INVALID_GROUP_NAME,
    "INVALID_PLANNER": PlanningError.INVALID_PLANNER,
    "INVALID_JOINT_NAMES": PlanningError.INVALID_JOINT_NAMES,
    "INVALID_JOINT_COUNT": PlanningError.INVALID_JOINT_COUNT,
    "INVALID_STATE": PlanningError.INVALID_ROBOT_STATE,
    "START_IN_COLLISION": PlanningError.START_STATE_IN_COLLISION,
    "GOAL_IN_COLLISION": PlanningError.GOAL_IN_COLLISION,
    "NO_IK_SOLUTION": PlanningError.NO_IK_SOLUTION,
    "INVALID_SCENE": PlanningError.INVALID_SCENE,
    "INVALID_REQUEST": PlanningError.INVALID_REQUEST,
    "NO_START_STATE": PlanningError.NO_START_STATE,
    "INVALID_LINK": PlanningError.INVALID_LINK_NAME,
    "INVALID_OBJECT": PlanningError.INVALID_OBJECT_NAME,
    "OBJECT_ALREADY_ATTACHED": PlanningError.OBJECT_ALREADY_ATTACHED,
    "START_VIOLATES_CONSTRAINTS": PlanningError.START_STATE_VIOLATES_PATH_CONSTRAINTS,
    "BUSY": PlanningError.BUSY,
}

CODE_NAMES: dict[int, str] = {
    getattr(PlanningError, name): name
    for name in dir(PlanningError)
    if name.isupper() and isinstance(getattr(PlanningError, name), int)
}


def code_name(code: int) -> str:
    """``PlanningError`` constant name of ``code`` (e.g. ``-16`` -> ``"INVALID_PLANNER"``)."""
    return CODE_NAMES.get(code, f"UNKNOWN({code})")


def error_code(exc: BaseException) -> int:
    """``PlanningError`` code of a core exception (via its status); INTERNAL_ERROR for anything else."""
    status = known_status_of_error(exc)
    return PlanningError.INTERNAL_ERROR if status is None else STATUS_CODES[status.name]


def error_msg(exc: BaseException | None = None, *, source: str = "") -> PlanningError:
    """``PlanningError`` for ``exc`` (None = SUCCESS)."""
    if exc is None:
        return PlanningError(code=PlanningError.SUCCESS, message="", source=source)
    message = str(exc) if isinstance(exc, errors.MaruError) else f"{type(exc).__name__}: {exc}"
    return PlanningError(
        code=error_code(exc), message=errors.one_line(message), source=getattr(exc, "source", source) or source
    )


def result_error_msg(result) -> PlanningError:
    """``PlanningError`` for a core ``MotionResult`` (status + typed error + message)."""
    if result.success:
        return PlanningError(code=PlanningError.SUCCESS, message=result.message or "", source="")
    if result.error is not None:
        err = error_msg(result.error)
        if err.code != PlanningError.INTERNAL_ERROR:
            return err
    status = getattr(result.status, "name", str(result.status))
    code = STATUS_CODES.get(status, PlanningError.INTERNAL_ERROR)
    source = getattr(result.error, "source", "") if result.error is not None else "planner"
    return PlanningError(code=code, message=errors.one_line(result.message or status), source=source or "planner")


# ---------------------------------------------------------------- joint values


def named_values(names, values, what: str) -> dict[str, float]:
    """``{name: value}`` from parallel name/value arrays, checked for length and duplicates."""
    names = list(names)
    values = list(values)
    if len(names) != len(values):
        raise errors.InvalidJointCount(f"{what}: {len(names)} joint names but {len(values)} positions")
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise errors.InvalidJointNames(f"{what}: joint '{name}' appears twice")
        seen.add(name)
    return {name: float(value) for name, value in zip(names, values, strict=True)}


def joint_state_values(msg, what: str = "start_state") -> dict[str, float]:
    """Positions of a ``sensor_msgs/JointState`` by joint name."""
    return named_values(msg.name, msg.position, what)


def joint_state_msg(names, positions, stamp=None):
    """``sensor_msgs/JointState`` with positions only."""
    msg = JointState()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.name = list(names)
    msg.position = [float(v) for v in positions]
    return msg


# ---------------------------------------------------------------- poses


def quaternion_to_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    """3x3 rotation of a (normalised) quaternion."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quaternion(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a 3x3 rotation matrix (Shepperd's method)."""
    m = np.asarray(rotation, dtype=float)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        w, x, y, z = 0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        w, x, y, z = (m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        w, x, y, z = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        w, x, y, z = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s
    return float(x), float(y), float(z), float(w)


def pose_to_matrix(pose, what: str = "pose") -> np.ndarray:
    """4x4 homogeneous transform of a ``geometry_msgs/Pose``; the quaternion is normalised.

    Raises ``InvalidRequest`` for NaN/inf fields or a zero quaternion.
    """
    p, o = pose.position, pose.orientation
    values = [p.x, p.y, p.z, o.x, o.y, o.z, o.w]
    if not all(math.isfinite(v) for v in values):
        raise errors.InvalidRequest(f"{what}: position/orientation has a NaN or infinite value")
    norm = math.hypot(o.x, o.y, o.z, o.w)  # no overflow for huge components (a sum of squares raised)
    if norm < 1e-9:
        raise errors.InvalidRequest(f"{what}: orientation quaternion is zero")
    transform = np.eye(4)
    transform[:3, :3] = quaternion_to_matrix(o.x / norm, o.y / norm, o.z / norm, o.w / norm)
    transform[:3, 3] = [p.x, p.y, p.z]
    return transform


def matrix_to_pose(transform) -> Pose:
    """``geometry_msgs/Pose`` of a 4x4 homogeneous transform."""
    t = np.asarray(transform, dtype=float)
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in t[:3, 3])
    q = matrix_to_quaternion(t[:3, :3])
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = q
    return pose


def pose_goals(poses, links, planning_frame: str) -> dict[str, np.ndarray]:
    """``{link: 4x4}`` from ``goal_poses`` + ``goal_links``; poses must be in the planning frame."""
    poses, links = list(poses), list(links)
    if len(poses) != len(links):
        raise errors.InvalidRequest(f"{len(poses)} goal_poses but {len(links)} goal_links (one link per pose)")
    goals: dict[str, np.ndarray] = {}
    for stamped, link in zip(poses, links, strict=True):
        frame = stamped.header.frame_id
        if frame not in ("", planning_frame):
            raise errors.InvalidRequest(
                f"goal pose for '{link}' is in frame '{frame}'; only '{planning_frame}' is supported (no tf here)"
            )
        if link in goals:
            raise errors.InvalidRequest(f"goal link '{link}' appears twice")
        goals[link] = pose_to_matrix(stamped.pose, what=f"goal pose for '{link}'")
    return goals


# ---------------------------------------------------------------- scene obstacles


def obstacle_pose(pose: Pose, name: str) -> np.ndarray:
    """4x4 pose of obstacle ``name``; a NaN or zero-quaternion pose raises ``InvalidScene``."""
    try:
        return pose_to_matrix(pose, what=f"obstacle '{name}' pose")
    except errors.InvalidRequest as exc:
        raise errors.InvalidScene(str(exc)) from None


def primitive_shape(type_code: int, where: str) -> shapes.ShapeSpec:
    """The shape table entry sent as ``SolidPrimitive`` type ``type_code``."""
    names = {
        getattr(SolidPrimitive, spec.primitive_type): spec for spec in shapes.SHAPES.values() if spec.primitive_type
    }
    if type_code not in names:
        known = ", ".join(f"{spec.primitive_type} ({code})" for code, spec in names.items())
        raise errors.InvalidScene(f"{where}: shape type {type_code} is not one of {known}")
    return names[type_code]


def primitive_to_obstacle(name: str, shape: SolidPrimitive, pose: Pose) -> dict:
    """Scene obstacle dict (``Scene.from_dict`` schema) of a named ``SolidPrimitive`` at ``pose``."""
    if not name:
        raise errors.InvalidScene("obstacle has an empty name")
    where = f"obstacle '{name}'"
    spec = primitive_shape(shape.type, where)
    dimensions = spec.from_primitive_values(where, shape.dimensions)
    fields = {k: list(v) if isinstance(v, tuple) else v for k, v in dimensions.items()}
    return {"name": name, "type": spec.name, **fields, "pose": obstacle_pose(pose, name).tolist()}


def primitive_msg(shape_name: str, dimensions, where: str = "obstacle") -> SolidPrimitive:
    """``SolidPrimitive`` of a shape of the table given by name, with its dimensions as listed."""
    spec = shapes.shape(shape_name, where)
    if spec.primitive_type is None:
        raise errors.InvalidScene(f"{where}: a {spec.name} has no SolidPrimitive form")
    return SolidPrimitive(type=getattr(SolidPrimitive, spec.primitive_type), dimensions=[float(v) for v in dimensions])


def obstacle_to_msg(obstacle: dict, frame_id: str) -> SceneObstacle:
    """``SceneObstacle`` (operation ADD) of a scene obstacle dict.

    A shape without a ``SolidPrimitive`` form (a mesh) keeps shape type 0 (the scene YAML carries it).
    """
    msg = SceneObstacle(name=obstacle["name"], operation=SceneObstacle.ADD)
    msg.header.frame_id = frame_id
    where = f"obstacle '{obstacle['name']}'"
    spec = shapes.shape(obstacle["type"], where)
    if spec.primitive_type is not None:
        msg.shape = primitive_msg(spec.name, spec.primitive_values(obstacle), where)
    msg.pose = matrix_to_pose(pose_matrix(obstacle.get("pose"), where))
    return msg


# ---------------------------------------------------------------- trajectories and stats


def duration_msg(seconds: float) -> Duration:
    sec = math.floor(seconds)
    nanosec = int(round((seconds - sec) * 1e9))
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return Duration(sec=int(sec), nanosec=nanosec)


def duration_seconds(duration) -> float:
    return duration.sec + duration.nanosec * 1e-9


def trajectory_msg(trajectory, frame_id: str, stamp=None) -> JointTrajectory:
    """``JointTrajectory`` of a core trajectory (joint_names, times, positions, velocities, accelerations)."""
    msg = JointTrajectory()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.joint_names = list(trajectory.joint_names)
    positions = np.asarray(trajectory.positions, dtype=float)
    velocities = _optional_rows(trajectory, "velocities", positions.shape)
    accelerations = _optional_rows(trajectory, "accelerations", positions.shape)
    for i, t in enumerate(np.asarray(trajectory.times, dtype=float)):
        point = JointTrajectoryPoint()
        # array('d') is taken as is by the message (a list is checked element by element)
        point.positions = _doubles(positions[i])
        if velocities is not None:
            point.velocities = _doubles(velocities[i])
        if accelerations is not None:
            point.accelerations = _doubles(accelerations[i])
        point.time_from_start = duration_msg(float(t))
        msg.points.append(point)
    return msg


def _doubles(row: np.ndarray) -> array.array:
    values = array.array("d")
    values.frombytes(np.ascontiguousarray(row, dtype=np.float64).tobytes())
    return values


def _optional_rows(trajectory, field: str, shape) -> np.ndarray | None:
    values = getattr(trajectory, field, None)
    if values is None:
        return None
    array = np.asarray(values, dtype=float)
    return array if array.shape == tuple(shape) else None


def trajectory_positions(msg: JointTrajectory) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(joint names, times (n,), positions (n, k)) of a ``JointTrajectory``."""
    times = np.array([duration_seconds(p.time_from_start) for p in msg.points])
    positions = np.array([list(p.positions) for p in msg.points], dtype=float)
    return list(msg.joint_names), times, positions


STATS_FIELDS_INT = ("nodes", "edges", "collision_checks", "waypoints", "seed", "repairs")
STATS_FIELDS_FLOAT = (
    "path_length",
    "smoothness",
    "validation_time",
    "ik_time",
    "solve_time",
    "simplify_time",
    "parameterize_time",
    "total_time",
    "certify_time",
    "min_clearance",
)


def stats_msg(stats) -> PlannerStats:
    """``PlannerStats`` of a core ``PlanStats`` (missing or None fields stay 0; seed None -> -1)."""
    msg = PlannerStats()
    if stats is None:
        return msg
    msg.planner_id = str(getattr(stats, "planner_id", "") or "")
    msg.certified = bool(getattr(stats, "certified", False))
    for field in STATS_FIELDS_INT:
        value = getattr(stats, field, None)
        if value is None:
            value = -1 if field == "seed" else 0
        setattr(msg, field, int(value))
    for field in STATS_FIELDS_FLOAT:
        value = getattr(stats, field, None)
        setattr(msg, field, float(value) if value is not None and math.isfinite(value) else 0.0)
    return msg
