"""Messages <-> core for the manipulation services of ``planning_node`` (docs/manipulation.md).

``compute_fk``, ``check_state_validity``, ``query_planners`` and ``compute_cartesian_path``: each has a
response filler here; what runs on a planning worker is the runtime's (:mod:`maru_planner.runtime.requests`,
its ``*_in_context`` functions re-exported here). Attach/detach operations of ``ApplyScene`` become the
runtime's scene edits in :func:`attachment_edit`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from geometry_msgs.msg import PoseStamped

from maru_planner import errors
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult
from maru_planner.planning.constraints import (
    OrientationConstraint,
    PathConstraints,
    PositionConstraint,
    RelativePoseConstraint,
)
from maru_planner.planning.links import check_link
from maru_planner.planning.queries import PlannerDescription, StateValidity
from maru_planner.planning.requests import start_configuration
from maru_planner.ros import planning_conversions as conv
from maru_planner.runtime.requests import cartesian_in_context, fk_in_context, validity_in_context
from maru_planner.runtime.scene_store import Attachments, AttachObject, DetachObject, LinkPose, apply_edit
from maru_planner.scene import Scene
from maru_planner_interfaces.msg import PathConstraints as PathConstraintsMsg
from maru_planner_interfaces.msg import PlannerDescription as PlannerDescriptionMsg
from maru_planner_interfaces.msg import PlannerParameter, SceneObstacle
from maru_planner_interfaces.srv import CheckStateValidity, ComputeCartesianPath, ComputeFK, QueryPlanners

DEFAULT_MAX_STEP = 0.01  # m, when a Cartesian request gives 0

__all__ = [  # what runs on a worker and the attachments moved to maru_planner.runtime; re-exported
    "Attachments",
    "LinkPose",
    "cartesian_in_context",
    "fk_in_context",
    "validity_in_context",
]


# ---------------------------------------------------------------- path constraints


def path_constraints(
    msg: PathConstraintsMsg, frame: str, robot: Any = None, start: Mapping[str, float] | None = None
) -> PathConstraints:
    """Core constraints of a ``PathConstraints`` message (empty link names: no such constraint).

    A relative pose with an all-zero quaternion is the links' relative pose at ``start`` (joint values by name;
    joints it lacks at neutral) on ``robot``: both are needed for that form.
    """
    orientation = position = None
    if msg.orientation_link:
        q = msg.orientation
        norm = math.hypot(q.x, q.y, q.z, q.w)
        if not (math.isfinite(norm) and norm > 1e-9):
            raise errors.InvalidRequest("path_constraints.orientation: the quaternion is zero or not finite")
        rotation = conv.quaternion_to_matrix(q.x / norm, q.y / norm, q.z / norm, q.w / norm)
        t = msg.orientation_tolerance
        orientation = OrientationConstraint(msg.orientation_link, rotation, np.array([t.x, t.y, t.z]))
    if msg.position_link:
        box = conv.pose_to_matrix(msg.box_pose, "path_constraints.box_pose")
        s = msg.box_size
        position = PositionConstraint(msg.position_link, box, np.array([s.x, s.y, s.z]))
    relative = relative_constraint(msg, robot, start) if msg.relative_link_a or msg.relative_link_b else None
    return PathConstraints(orientation, position, relative)


def relative_constraint(
    msg: PathConstraintsMsg, robot: Any, start: Mapping[str, float] | None
) -> RelativePoseConstraint:
    """The relative-pose part of ``msg`` (see :func:`path_constraints`)."""
    what = "path_constraints.relative"
    if not (msg.relative_link_a and msg.relative_link_b):
        raise errors.InvalidRequest(f"{what}: give both relative_link_a and relative_link_b")
    tolerances = {}
    for name, value in (("position_tolerance", msg.relative_position_tolerance),
                        ("orientation_tolerance", msg.relative_orientation_tolerance)):  # fmt: skip
        if not (math.isfinite(value) and value >= 0.0):
            raise errors.InvalidRequest(f"{what}_{name} must be finite and >= 0 (0 = default), got {value}")
        if value > 0.0:
            tolerances[name] = float(value)
    link_a, link_b = msg.relative_link_a, msg.relative_link_b
    q = msg.relative_pose.orientation
    if (q.x, q.y, q.z, q.w) != (0.0, 0.0, 0.0, 0.0):
        relative = conv.pose_to_matrix(msg.relative_pose, f"{what}_pose")
        return RelativePoseConstraint(link_a, link_b, relative, **tolerances)
    if robot is None or not start:
        raise errors.InvalidRequest(f"{what}_pose: a zero quaternion (held at the start) needs a start state here")
    for link in (link_a, link_b):
        check_link(robot, link, "path constraint link")
    q_start = start_configuration(robot, dict(start), [])
    return RelativePoseConstraint.held(robot, q_start, link_a, link_b, **tolerances)


# ---------------------------------------------------------------- compute_fk


def fill_fk(response: ComputeFK.Response, poses: Mapping[str, np.ndarray], frame: str, stamp) -> None:
    response.links = list(poses)
    response.poses = [_stamped(pose, frame, stamp) for pose in poses.values()]


def _stamped(pose: np.ndarray, frame: str, stamp) -> PoseStamped:
    msg = PoseStamped(pose=conv.matrix_to_pose(pose))
    msg.header.frame_id = frame
    msg.header.stamp = stamp
    return msg


# ---------------------------------------------------------------- check_state_validity


def fill_validity(response: CheckStateValidity.Response, answer: StateValidity) -> None:
    response.valid = answer.valid
    response.contact_first = [a for a, _ in answer.colliding_pairs]
    response.contact_second = [b for _, b in answer.colliding_pairs]
    response.clearance = float(answer.clearance) if math.isfinite(answer.clearance) else math.inf
    response.closest_pair = [name for name in answer.closest_pair if name]
    response.orientation_violation = answer.orientation_violation
    response.position_violation = answer.position_violation


# ---------------------------------------------------------------- query_planners


def fill_planners(response: QueryPlanners.Response, planners: list[PlannerDescription], default: str) -> None:
    response.default_planner = default
    response.planners = [_planner_msg(p) for p in planners]


def _planner_msg(planner: PlannerDescription) -> PlannerDescriptionMsg:
    msg = PlannerDescriptionMsg(id=planner.id, description=planner.description, capabilities=list(planner.capabilities))
    for parameter in planner.parameters:
        d = parameter.as_dict()
        msg.parameters.append(PlannerParameter(
            name=d["name"], type=d["type"], default_value=_scalar(d["default"]), current_value=_scalar(d["current"]),
            lower=float(d["lower"]), upper=float(d["upper"]), choices=d["choices"], description=d["description"],
        ))  # fmt: skip
    return msg


def _scalar(value) -> str:
    """A YAML scalar: true/false, numbers as Python prints them, strings as they are."""
    return str(value).lower() if isinstance(value, bool) else str(value)


# ---------------------------------------------------------------- compute_cartesian_path


def cartesian_request(msg: ComputeCartesianPath.Request, start: dict[str, float], group: str, frame: str,
                      budget: float) -> CartesianRequest:  # fmt: skip
    """Core request of a ``ComputeCartesianPath`` request (waypoints are poses in the planning frame)."""
    waypoints = [conv.pose_to_matrix(p, f"waypoint {k}") for k, p in enumerate(msg.waypoints)]
    return CartesianRequest(
        group=msg.group or group, start=start, waypoints=waypoints, link=msg.link,
        max_step=msg.max_step if msg.max_step != 0.0 else DEFAULT_MAX_STEP, jump_threshold=msg.jump_threshold,
        avoid_collisions=msg.avoid_collisions,
        velocity_scaling=msg.max_velocity_scaling_factor or 1.0,
        acceleration_scaling=msg.max_acceleration_scaling_factor or 1.0, time_budget=budget,
    )  # fmt: skip


def fill_cartesian(response: ComputeCartesianPath.Response, result: CartesianResult, frame: str, stamp) -> None:
    response.error = conv.result_error_msg(result)
    response.fraction = float(result.fraction)
    response.stop_reason = result.stop_reason
    if result.trajectory is not None:
        response.trajectory = conv.trajectory_msg(result.trajectory, frame, stamp)


# ---------------------------------------------------------------- attach / detach


def attachment_edit(msg: SceneObstacle) -> AttachObject | DetachObject:
    """ATTACH (a scene obstacle where it is, or a new shape at ``msg.pose``) or DETACH ``msg.name``, as an edit.

    The link is placed at ``msg.robot_state`` (empty: the latest /joint_states). A new shape's pose is in the
    planning frame, like an ADD's; it is converted once the link is placed.
    """
    values = conv.joint_state_values(msg.robot_state, f"object '{msg.name}' robot_state")
    if msg.operation == SceneObstacle.DETACH:
        return DetachObject(msg.name, values)
    if not msg.link_name:
        raise errors.InvalidLink(f"object '{msg.name}': ATTACH needs a link_name")
    shape = None  # no shape: the scene obstacle of that name
    if msg.shape.type != 0:
        shape = functools.partial(conv.primitive_to_obstacle, msg.name, msg.shape, msg.pose)
    return AttachObject(msg.name, msg.link_name, values, tuple(msg.touch_links), shape)


def apply_attachment(scene: Scene, msg: SceneObstacle, frame: str, link_pose: LinkPose) -> None:
    """Apply :func:`attachment_edit` of ``msg`` to ``scene``, ``link_pose(link, joint values)`` placing the link
    (``frame``, the planning frame, is checked by the caller)."""
    apply_edit(scene, attachment_edit(msg), link_pose)
