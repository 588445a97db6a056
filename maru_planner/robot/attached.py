"""The robot with its attached objects: each attached object becomes a body of the collision model.

:func:`robot_with_attached` returns a :class:`RobotModel` whose Pinocchio model has one extra frame per
attached object (named after the object, on its link's joint) and whose collision model has the
object's geometry on that frame. Joints, limits and groups are the robot's, so configurations are
shared. Every checker built on it -- the exact :class:`~maru_planner.collision.CollisionChecker`,
the sphere checker (which fits spheres to every collision geometry) and the path certifier --
therefore moves the object with its link and checks it against the scene and the robot's links.
Self-collision: the object is never checked against its own link nor its ``touch_links`` (added to
the SRDF's disabled pairs). :class:`~maru_planner.planning.MotionPlanner` rebuilds its checkers when
the scene's attached objects change.

Here rather than in ``collision/``: this builds a robot model (as MoveIt's ``robot_state`` owns its
``AttachedBody``), checks nothing; the scene only holds what is attached (:class:`~maru_planner.scene.AttachedObject`).
"""

from __future__ import annotations

import copy

import pinocchio as pin

from maru_planner.errors import InvalidLink, ObjectAlreadyAttached
from maru_planner.robot.model import RobotModel
from maru_planner.scene.obstacle import AttachedObject
from maru_planner.scene.planning_scene import Scene


class CarryingRobot(RobotModel):
    """A robot with attached objects as bodies: ``base_robot`` without them, ``attachment_key`` what they are."""

    base_robot: RobotModel
    attachment_key: tuple


def attachment_key(scene_or_robot) -> tuple:
    """What the attached objects of a scene (or carried by a robot) look like; equal keys, same geometry."""
    attached = getattr(scene_or_robot, "attached", None)
    if isinstance(attached, dict):
        return tuple(a.key() for a in attached.values())
    return getattr(scene_or_robot, "attachment_key", ())


def base_robot(robot):
    """The robot without attached objects (``robot`` itself when it carries none)."""
    return getattr(robot, "base_robot", robot)


def check_attachments(robot: RobotModel, scene: Scene) -> None:
    """InvalidLink for an attached object on (or touching) a link the robot does not have; a name clash raises."""
    model = base_robot(robot).model
    for item in scene.attached.values():
        for link in (item.link, *item.touch_links):
            if not model.existFrame(link):
                raise InvalidLink(f"attached object '{item.name}': {link!r} is not a link of {robot.name}")
        if model.existFrame(item.name):
            raise ObjectAlreadyAttached(f"attached object '{item.name}': the robot has a link of that name")


def robot_with_attached(robot: RobotModel, scene: Scene | None) -> RobotModel:
    """``robot`` (its base, if it already carries objects) with ``scene``'s attached objects as bodies."""
    base = base_robot(robot)
    if scene is None or not getattr(scene, "attached", None):
        return base
    check_attachments(base, scene)
    model = pin.Model(base.model)
    geometry = base.collision_model.copy()
    srdf = copy.deepcopy(base.srdf)
    for item in scene.attached.values():
        _add_body(model, geometry, item)
        srdf.disabled_pairs.update(frozenset((item.name, link)) for link in (item.link, *item.touch_links))
    carrying = CarryingRobot(
        base.name, model, geometry, srdf,
        acceleration_limits=base.acceleration_limits, end_effectors=base.end_effectors,
        ik_strategies=base.ik_strategies,
    )  # fmt: skip
    carrying.skip_adjacent_pairs = base.skip_adjacent_pairs  # the added disabled pairs must not change the rule
    carrying.groups = copy.deepcopy(base.groups)
    carrying.named_states = dict(base.named_states)
    carrying.sphere_options = base.sphere_options
    carrying.base_robot = base
    carrying.attachment_key = attachment_key(scene)
    return carrying


def _add_body(model: pin.Model, geometry: pin.GeometryModel, item: AttachedObject) -> None:
    link = model.frames[model.getFrameId(item.link)]
    parent_frame = model.getFrameId(item.link)
    placement = link.placement * pin.SE3(item.obstacle.pose[:3, :3].copy(), item.obstacle.pose[:3, 3].copy())
    frame = model.addFrame(pin.Frame(item.name, link.parentJoint, parent_frame, placement, pin.FrameType.BODY))
    body = pin.GeometryObject(f"attached/{item.name}", link.parentJoint, frame, placement, item.obstacle.geometry())
    geometry.addGeometryObject(body)
