"""MoveIt planning-scene and motion-request YAML (as MotionBenchMaker writes them) to our types.

MoveIt conventions honoured here:
- ``world.collision_objects[*]``: ``id``, ``primitives`` (``type`` + ``dimensions``) and
  ``primitive_poses`` (``position``, ``orientation`` as a quaternion **x y z w**), optionally an object
  ``pose`` that the primitive poses are relative to (MoveIt >= 2); ``operation`` REMOVE is skipped.
- Primitive types and dimensions come from the shape table (``maru_planner/scene/shapes.py``): box
  ``[x, y, z]`` (full sides), sphere ``[radius]``, cylinder **``[height, radius]``** (along local z, centred).
- The robot's root is placed by ``robot_state.multi_dof_joint_state`` (``virtual_joint``); obstacles are
  expressed in the robot's root frame (identity in MotionBenchMaker's problems).
- Requests: ``start_state.joint_state`` (``name``, ``position``) and the goal as the first
  ``goal_constraints[*].joint_constraints`` list (``joint_name``, ``position``).

Unsupported content (meshes, planes, cones) raises :class:`~maru_planner.errors.InvalidScene`
naming the object, rather than being dropped silently.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from maru_planner.errors import InvalidRequest, InvalidScene, one_line
from maru_planner.scene.obstacle import Obstacle
from maru_planner.scene.planning_scene import Scene
from maru_planner.scene.shapes import by_primitive_type, numbers


@dataclass
class MoveItRequest:
    """The parts of a MoveIt ``MotionPlanRequest`` a joint-space planning problem needs."""

    group: str
    start: dict[str, float]
    goal: dict[str, float]
    planner_id: str = ""
    allowed_planning_time: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)


def quaternion_matrix(xyzw) -> np.ndarray:
    """Rotation matrix of a quaternion given as x, y, z, w (normalised here; zero raises)."""
    q = np.asarray(xyzw, dtype=float).reshape(-1)
    if q.size != 4 or not np.all(np.isfinite(q)):
        raise InvalidScene(f"orientation must be 4 finite numbers x y z w, got {xyzw!r}")
    n = np.linalg.norm(q)
    if n < 1e-12:
        raise InvalidScene("orientation quaternion has zero norm")
    x, y, z, w = q / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def pose_from_msg(pose: Mapping | None, where: str) -> np.ndarray:
    """4x4 from a geometry_msgs/Pose-like mapping ``{position: [x, y, z], orientation: [x, y, z, w]}``.

    Both the flow-list form MotionBenchMaker writes and the ``{x: .., y: ..}`` mapping form are accepted.
    """
    T = np.eye(4)
    if pose is None:
        return T
    if not isinstance(pose, Mapping):
        raise InvalidScene(f"{where}: pose must be a mapping with position and orientation, got {pose!r}")
    position = _vector(pose.get("position", [0, 0, 0]), "xyz", where, "position")
    orientation = _vector(pose.get("orientation", [0, 0, 0, 1]), "xyzw", where, "orientation")
    T[:3, 3] = position
    T[:3, :3] = quaternion_matrix(orientation)
    return T


def _vector(value: Any, keys: str, where: str, name: str) -> np.ndarray:
    if isinstance(value, Mapping):
        value = [value.get(k, 1.0 if k == "w" else 0.0) for k in keys]
    return numbers(where, name, value, len(keys))


def _load_yaml(source: str | Path | Mapping, kind: str) -> dict:
    if isinstance(source, Mapping):
        return dict(source)
    text = str(source)
    if isinstance(source, Path) or ("\n" not in text and text.endswith((".yaml", ".yml"))):
        path = Path(source)
        if not path.is_file():
            raise (InvalidScene if kind == "scene" else InvalidRequest)(f"{kind} file not found: {path}")
        text = path.read_text()
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        error = InvalidScene if kind == "scene" else InvalidRequest
        raise error(f"{kind} YAML does not parse: {one_line(exc, 160)}") from None
    if not isinstance(data, dict):
        raise (InvalidScene if kind == "scene" else InvalidRequest)(f"{kind} YAML must be a mapping")
    return data


def primitive_obstacle(name: str, primitive: Mapping, pose: np.ndarray) -> Obstacle:
    """One ``shape_msgs/SolidPrimitive`` as an :class:`Obstacle` (shape looked up by primitive type)."""
    where = f"collision object '{name}'"
    spec = by_primitive_type(str(primitive.get("type", "")), where)
    dimensions = spec.from_primitive_values(where, primitive.get("dimensions") or [])
    return Obstacle(name, spec.name, pose=pose, **dimensions)


def robot_root_pose(data: Mapping) -> np.ndarray:
    """World pose of the robot root from ``robot_state.multi_dof_joint_state`` (identity if absent)."""
    multi = ((data.get("robot_state") or {}).get("multi_dof_joint_state")) or {}
    transforms = multi.get("transforms") or []
    if not transforms:
        return np.eye(4)
    tf = transforms[0]
    return pose_from_msg(
        {"position": tf.get("translation", [0, 0, 0]), "orientation": tf.get("rotation")},
        "robot_state.multi_dof_joint_state",
    )


def scene_from_moveit(source: str | Path | Mapping) -> Scene:
    """A MoveIt ``PlanningScene`` YAML (file, string or parsed mapping) as a :class:`Scene`.

    Obstacles are named by the object id, with ``/<k>`` appended when an object has several primitives.
    """
    data = _load_yaml(source, "scene")
    world = data.get("world") or {}
    objects = world.get("collision_objects") or []
    if not isinstance(objects, list):
        raise InvalidScene("scene: world.collision_objects must be a list")
    root_inv = np.linalg.inv(robot_root_pose(data))
    scene = Scene()
    for i, obj in enumerate(objects):
        if not isinstance(obj, Mapping):
            raise InvalidScene(f"collision object #{i} must be a mapping")
        name = str(obj.get("id") or f"object{i}")
        if str(obj.get("operation", "ADD")).upper() in ("REMOVE", "1"):
            continue
        for extra in ("meshes", "planes"):
            if obj.get(extra):
                raise InvalidScene(f"collision object '{name}': {extra} are not supported (primitives only)")
        primitives = obj.get("primitives") or []
        poses = obj.get("primitive_poses") or []
        if len(poses) != len(primitives):
            raise InvalidScene(f"collision object '{name}': {len(primitives)} primitives but {len(poses)} poses")
        object_pose = pose_from_msg(obj.get("pose"), f"collision object '{name}'")
        for k, (primitive, pose) in enumerate(zip(primitives, poses)):
            label = name if len(primitives) == 1 else f"{name}/{k}"
            if label in scene:
                raise InvalidScene(f"scene: duplicate collision object id '{label}'")
            world_pose = object_pose @ pose_from_msg(pose, f"collision object '{label}'")
            scene.add(primitive_obstacle(label, primitive, root_inv @ world_pose))
    return scene


def request_from_moveit(source: str | Path | Mapping, fixed_joints: Mapping[str, float] | None = None) -> MoveItRequest:
    """A MoveIt ``MotionPlanRequest`` YAML as start and goal joint dictionaries.

    ``fixed_joints`` (e.g. :data:`~maru_planner.robot.robots.panda.PANDA_FINGERS_OPEN`) override the start
    state and are added to the goal, so joints the request does not plan keep one value along the path.
    """
    data = _load_yaml(source, "request")
    joint_state = (data.get("start_state") or {}).get("joint_state") or {}
    names, positions = joint_state.get("name") or [], joint_state.get("position") or []
    if len(names) != len(positions):
        raise InvalidRequest(f"request: start_state has {len(names)} joint names but {len(positions)} positions")
    start = {str(n): float(p) for n, p in zip(names, positions)}
    constraints = data.get("goal_constraints") or []
    if not constraints or not (constraints[0] or {}).get("joint_constraints"):
        raise InvalidRequest("request: no joint_constraints in goal_constraints (only joint goals are supported)")
    goal = {}
    for c in constraints[0]["joint_constraints"]:
        if "joint_name" not in c or "position" not in c:
            raise InvalidRequest(f"request: joint constraint without joint_name/position: {c!r}")
        goal[str(c["joint_name"])] = float(c["position"])
    for values, label in ((start, "start"), (goal, "goal")):
        bad = [n for n, v in values.items() if not np.isfinite(v)]
        if bad:
            raise InvalidRequest(f"request: {label} has non-finite values for {bad}")
    for joint, value in (fixed_joints or {}).items():
        start[joint] = float(value)
        goal.setdefault(joint, float(value))
    return MoveItRequest(
        group=str(data.get("group_name", "")),
        start=start,
        goal=goal,
        planner_id=str(data.get("planner_id", "")),
        allowed_planning_time=float(data.get("allowed_planning_time", 0.0) or 0.0),
    )
