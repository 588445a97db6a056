"""Messages <-> core for the manipulation services of ``planning_node`` (docs/manipulation.md).

``compute_fk``, ``check_state_validity``, ``query_planners`` and ``compute_cartesian_path``: each has a
response filler here and, where it needs a worker's robot and checker, a ``*_in_context`` function the
node runs on a planning worker. Attach/detach operations of ``ApplyScene`` are applied by
:func:`apply_attachment`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np
from geometry_msgs.msg import PoseStamped

from maru_planner import errors
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult
from maru_planner.planning.constraints import OrientationConstraint, PathConstraints, PositionConstraint
from maru_planner.planning.queries import PlannerDescription, StateValidity, check_state_validity, compute_fk
from maru_planner.ros import planning_conversions as conv
from maru_planner.scene import Obstacle, Scene
from maru_planner.scene_attached import check_attachments
from maru_planner_interfaces.msg import PathConstraints as PathConstraintsMsg
from maru_planner_interfaces.msg import PlannerDescription as PlannerDescriptionMsg
from maru_planner_interfaces.msg import PlannerParameter, SceneObstacle
from maru_planner_interfaces.srv import CheckStateValidity, ComputeCartesianPath, ComputeFK, QueryPlanners

DEFAULT_MAX_STEP = 0.01  # m, when a Cartesian request gives 0

LinkPose = Callable[[str, dict[str, float]], np.ndarray]  # (link, joint values) -> 4x4 pose in the planning frame


# ---------------------------------------------------------------- path constraints

def path_constraints(msg: PathConstraintsMsg, frame: str) -> PathConstraints:
    """Core constraints of a ``PathConstraints`` message (empty link names: no such constraint)."""
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
    return PathConstraints(orientation, position)


# ---------------------------------------------------------------- compute_fk

def fk_in_context(context, values: dict[str, float], links: list[str]) -> dict[str, np.ndarray]:
    robot = context.planner.robot
    return compute_fk(robot, conv.configuration(robot, values, strict=True), links)


def fill_fk(response: ComputeFK.Response, poses: Mapping[str, np.ndarray], frame: str, stamp) -> None:
    response.links = list(poses)
    response.poses = [_stamped(pose, frame, stamp) for pose in poses.values()]


def _stamped(pose: np.ndarray, frame: str, stamp) -> PoseStamped:
    msg = PoseStamped(pose=conv.matrix_to_pose(pose))
    msg.header.frame_id = frame
    msg.header.stamp = stamp
    return msg


# ---------------------------------------------------------------- check_state_validity

def validity_in_context(context, values: dict[str, float], constraints: PathConstraints) -> StateValidity:
    planner = context.planner
    constraints.check_links(planner.robot)
    q = conv.configuration(planner.robot, values, strict=True)
    return check_state_validity(planner.robot, planner.exact_checker or planner.checker, q, constraints)


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


def cartesian_in_context(context, request: CartesianRequest) -> CartesianResult:
    return context.planner.cartesian_path(request)


def fill_cartesian(response: ComputeCartesianPath.Response, result: CartesianResult, frame: str, stamp) -> None:
    response.error = conv.result_error_msg(result)
    response.fraction = float(result.fraction)
    response.stop_reason = result.stop_reason
    if result.trajectory is not None:
        response.trajectory = conv.trajectory_msg(result.trajectory, frame, stamp)


# ---------------------------------------------------------------- attach / detach

class Attachments:
    """What ATTACH/DETACH need from the node: link poses of its robot, and a check of the attached links.

    ``latest`` returns the latest /joint_states values (used when an operation's robot_state is empty).
    Thread-safe: every pose comes from its own Pinocchio data.
    """

    def __init__(self, robot, latest: Callable[[], dict[str, float]]):
        self.robot, self.latest = robot, latest

    def link_pose(self, link: str, values: dict[str, float]) -> np.ndarray:
        if not values:
            values = self.latest()
            if not values:
                raise errors.NoStartState("robot_state is empty and no /joint_states message has been received")
        return compute_fk(self.robot, conv.configuration(self.robot, values), [link])[link]

    def check(self, scene: Scene) -> None:
        """InvalidLink / ObjectAlreadyAttached for attached objects the robot cannot carry."""
        check_attachments(self.robot, scene)


def apply_attachment(scene: Scene, msg: SceneObstacle, frame: str, link_pose: LinkPose) -> None:
    """ATTACH (a scene obstacle where it is, or a new shape at ``msg.pose``) or DETACH ``msg.name``.

    ``link_pose(link, joint values)`` places the link: the values are ``msg.robot_state``'s (empty: the
    caller's latest state). A new shape's pose is in the planning frame, like an ADD's.
    """
    values = conv.joint_state_values(msg.robot_state, f"object '{msg.name}' robot_state")
    if msg.operation == SceneObstacle.DETACH:
        if msg.name not in scene.attached:
            raise errors.InvalidObject(f"object '{msg.name}': not attached (attached: {list(scene.attached)})")
        scene.detach(msg.name, link_pose(scene.attached[msg.name].link, values))
        return
    if not msg.link_name:
        raise errors.InvalidLink(f"object '{msg.name}': ATTACH needs a link_name")
    here = link_pose(msg.link_name, values)
    if msg.shape.type == 0:  # no shape: the scene obstacle of that name
        scene.attach(msg.name, msg.link_name, here, touch_links=list(msg.touch_links))
        return
    shape = conv.primitive_to_obstacle(msg.name, msg.shape, msg.pose)
    local = np.linalg.inv(here) @ np.asarray(shape.pop("pose"))
    obstacle = Obstacle.from_dict({**shape, "pose": local})
    scene.attach(msg.name, msg.link_name, touch_links=list(msg.touch_links), obstacle=obstacle)
