"""A MuJoCo model of a fixed-base arm built from its URDF (through the planner's :class:`RobotModel`).

The kinematic tree, inertias, joint limits and effort limits are the URDF's as Pinocchio reads them (the
same reduced model the planner uses, so locked joints stay locked and attached objects sit where the
planner puts them). Collision geometry is the planner's: primitives as MuJoCo primitives, meshes as
meshes (MuJoCo collides their convex hulls). The scene's obstacles are static geoms of the world.

Servo: every joint has a position actuator (``kp``), a velocity actuator (``kv``, fed the desired
velocity) and a torque actuator fed the acceleration feedforward ``M(q) a_d`` (the arm's inertia, armature
included, times the desired accelerations, as model-based drives add), i.e.
``tau = kp (q_d - q) + kv (v_d - v) + [M(q) a_d]_i``, the total clamped to the URDF's effort limit
(``actfrcrange``), plus joint damping and a reflected rotor inertia (armature). ``kp`` is chosen per joint
from its effort limit (:class:`ServoGains`), ``kv`` for a damping ratio from the joint's inertia at
``q0``. Physics at 1 kHz with the ``implicitfast`` integrator.

Contacts: robot geoms (links and attached objects) collide only with obstacles (``contype``/``conaffinity``
bits), so every MuJoCo contact is a robot-obstacle contact; self-collision is the planner's job.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import coal
import mujoco
import numpy as np
import pinocchio as pin

from maru_planner.errors import InvalidRequest, InvalidScene
from maru_planner.robot.attached import robot_with_attached
from maru_planner.robot.model import RobotModel
from maru_planner.scene.planning_scene import Scene

TIMESTEP = 0.001  # s: 1 kHz physics
ROBOT_BITS = (1, 2)  # (contype, conaffinity) of robot geoms: they touch obstacles, not each other
OBSTACLE_BITS = (2, 1)  # (contype, conaffinity) of obstacle geoms: they touch the robot, not each other
OBSTACLE_PREFIX = "obstacle/"


@dataclass(frozen=True)
class ServoGains:
    """The joint servo: ``kp = effort_limit / saturation_error`` per joint, ``kv`` for ``damping_ratio``.

    ``saturation_error``: the position error at which a joint's spring alone reaches its effort limit.
    ``armature``: reflected rotor inertia (kg m^2) added to every joint (MuJoCo Menagerie's Panda uses 0.1).
    ``damping``: joint damping (N m s/rad) where the URDF gives none.
    ``acceleration_feedforward``: the servo adds ``M(q)`` times the desired accelerations (without it the
    position error is what accelerates the arm: lag on the way, settling after the end).
    ``gravity_compensation``: the servo adds the links' gravity torques (as the drives of Franka's and UR's arms
    do); MuJoCo's ``gravcomp`` routed through the actuators (``actgravcomp``), so it counts against the effort limit.
    """

    saturation_error: float = 0.02
    damping_ratio: float = 1.0
    armature: float = 0.1
    damping: float = 0.1
    gravity_compensation: bool = True
    acceleration_feedforward: bool = True

    def __post_init__(self) -> None:
        for name in ("saturation_error", "damping_ratio"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise InvalidRequest(f"servo gains: {name} must be a positive number, got {value!r}")
        for name in ("armature", "damping"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise InvalidRequest(f"servo gains: {name} must be a non-negative number, got {value!r}")


@dataclass
class ArmModel:
    """A compiled MuJoCo arm: ``joint_names`` in the planner's order; actuators ``[position..., velocity...,
    feedforward torque...]``."""

    model: mujoco.MjModel
    joint_names: list[str]
    effort_limits: np.ndarray
    kp: np.ndarray
    kv: np.ndarray
    lower_limits: np.ndarray
    upper_limits: np.ndarray
    velocity_limits: np.ndarray
    acceleration_limits: np.ndarray
    obstacle_names: list[str]
    qpos_index: np.ndarray  # MuJoCo qpos (= dof) address of each of joint_names
    geom_owners: list[str]  # per MuJoCo geom: its link, attached object or obstacle
    acceleration_feedforward: bool = True  # ServoGains.acceleration_feedforward

    @property
    def nq(self) -> int:
        return len(self.joint_names)

    def joint_indices(self, names: Sequence[str]) -> np.ndarray:
        """Indices of ``names`` in :attr:`joint_names`; InvalidJointNames naming the unknown ones."""
        from maru_planner.errors import InvalidJointNames  # lazy: keeps the error import beside its only use

        index = {n: i for i, n in enumerate(self.joint_names)}
        unknown = [n for n in names if n not in index]
        if unknown:
            raise InvalidJointNames(f"joints {unknown[:5]} are not in the simulated arm (has {self.joint_names})")
        if len(set(names)) != len(names):
            raise InvalidJointNames(f"joint names repeat: {list(names)}")
        return np.array([index[n] for n in names], dtype=int)

    def geom_owner(self, geom: int) -> str:
        """The link (or attached object, or obstacle) a geom belongs to."""
        return self.geom_owners[geom]

    def is_obstacle(self, geom: int) -> bool:
        return int(self.model.geom_contype[geom]) == OBSTACLE_BITS[0]


def build_arm_model(
    robot: RobotModel,
    scene: Scene | None = None,
    gains: ServoGains | None = None,
    q0: np.ndarray | None = None,
    payloads: Mapping[str, float] | None = None,
) -> ArmModel:
    """The arm of ``robot`` (with ``scene``'s attached objects) among ``scene``'s obstacles.

    ``q0``: the configuration the damping gains are tuned at (the robot's neutral one by default).
    ``payloads``: mass (kg) of attached objects by name (uniform density; others weigh nothing). The servos'
    gravity compensation does not know a payload (the drives are not told the load): the position loop holds it.
    """
    gains = gains or ServoGains()
    carrying = robot_with_attached(robot, scene)
    spec = mujoco.MjSpec()
    spec.modelname = robot.name
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.compiler.degree = False  # URDF limits are radians
    # links have explicit inertias; only a payload's body takes its inertia from its geom
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO
    bodies = _add_links(spec, carrying, gains, (robot.lower_limits, robot.upper_limits))
    owners = _add_robot_geoms(spec, carrying, bodies, _checked_payloads(payloads or {}, scene))
    obstacle_names = _add_obstacles(spec, scene)
    owners.update({OBSTACLE_PREFIX + name: name for name in obstacle_names})
    effort = np.asarray(carrying.model.effortLimit, dtype=float)
    kp = effort / gains.saturation_error
    for name in robot.joint_names:
        spec.add_actuator(name=f"position/{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT).set_to_position(
            kp=1.0
        )
    for name in robot.joint_names:
        spec.add_actuator(name=f"velocity/{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT).set_to_velocity(
            kv=1.0
        )
    for name in robot.joint_names:
        spec.add_actuator(name=f"feedforward/{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT).set_to_motor()
    model = spec.compile()
    qpos_index = np.array([model.jnt_qposadr[model.joint(name).id] for name in robot.joint_names], dtype=int)
    q_start = np.asarray(robot.neutral() if q0 is None else q0, dtype=float)
    kv = _damping_gains(model, kp, gains.damping_ratio, q_start, qpos_index)
    n = robot.nq
    model.actuator_gainprm[:n, 0], model.actuator_biasprm[:n, 1] = kp, -kp
    model.actuator_gainprm[n : 2 * n, 0], model.actuator_biasprm[n : 2 * n, 2] = kv, -kv
    return ArmModel(
        model=model,
        joint_names=list(robot.joint_names),
        effort_limits=effort,
        kp=kp,
        kv=kv,
        lower_limits=robot.lower_limits.copy(),
        upper_limits=robot.upper_limits.copy(),
        velocity_limits=robot.velocity_limits.copy(),
        acceleration_limits=robot.acceleration_limits.copy(),
        obstacle_names=obstacle_names,
        qpos_index=qpos_index,
        geom_owners=[owners.get(model.geom(g).name, "") for g in range(model.ngeom)],
        acceleration_feedforward=gains.acceleration_feedforward,
    )


def _add_links(
    spec: mujoco.MjSpec, robot: RobotModel, gains: ServoGains, limits: tuple[np.ndarray, np.ndarray]
) -> list[mujoco.MjsBody]:
    """One MuJoCo body per Pinocchio joint (index 0: the world), each with its joint, inertia and ``limits``
    (the robot's, which may differ from its URDF's, e.g. the MotionBenchMaker Panda's finger opening)."""
    model = robot.model
    bodies = [spec.worldbody]
    for j in range(1, model.njoints):
        placement = model.jointPlacements[j]
        body = bodies[model.parents[j]].add_body(
            name=model.names[j], pos=placement.translation, quat=_quat(placement.rotation)
        )
        inertia = model.inertias[j]
        body.explicitinertial = True
        body.mass = max(float(inertia.mass), 1e-6)
        body.ipos = inertia.lever
        body.fullinertia = _full_inertia(np.asarray(inertia.inertia), body.mass)
        body.gravcomp = 1.0 if gains.gravity_compensation else 0.0
        kind, axis = _joint_kind(model.joints[j], model.names[j])
        q = model.joints[j].idx_q
        body.add_joint(
            name=model.names[j],
            type=kind,
            axis=axis,
            range=[float(limits[0][q]), float(limits[1][q])],
            limited=mujoco.mjtLimited.mjLIMITED_TRUE,
            damping=float(model.damping[q]) or gains.damping,
            armature=gains.armature,
            actfrclimited=mujoco.mjtLimited.mjLIMITED_TRUE,
            actfrcrange=[-float(model.effortLimit[q]), float(model.effortLimit[q])],
            actgravcomp=gains.gravity_compensation,
        )
        bodies.append(body)
    return bodies


def _joint_kind(joint: pin.JointModel, name: str) -> tuple[mujoco.mjtJoint, list[float]]:
    axes = {"X": [1.0, 0.0, 0.0], "Y": [0.0, 1.0, 0.0], "Z": [0.0, 0.0, 1.0]}
    short_name = joint.shortname()
    kind = short_name.removeprefix("JointModel")
    if kind in ("RX", "RY", "RZ"):
        return mujoco.mjtJoint.mjJNT_HINGE, axes[kind[1]]
    if kind in ("PX", "PY", "PZ"):
        return mujoco.mjtJoint.mjJNT_SLIDE, axes[kind[1]]
    if kind in ("RevoluteUnaligned", "PrismaticUnaligned"):
        hinge = kind.startswith("Revolute")
        axis = [float(a) for a in joint.extract().axis]
        return (mujoco.mjtJoint.mjJNT_HINGE if hinge else mujoco.mjtJoint.mjJNT_SLIDE), axis
    raise InvalidRequest(f"joint '{name}': {short_name} has no MuJoCo counterpart here (revolute/prismatic only)")


def _full_inertia(inertia: np.ndarray, mass: float) -> list[float]:
    """``[ixx, iyy, izz, ixy, ixz, iyz]``, nudged to be positive definite (URDFs may give zeros)."""
    floor = 1e-6 * max(mass, 1e-3)
    inertia = inertia + floor * np.eye(3)
    return [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]


def _checked_payloads(payloads: Mapping[str, float], scene: Scene | None) -> dict[str, float]:
    attached = set(scene.attached) if scene is not None else set()
    for name, mass in payloads.items():
        if name not in attached:
            raise InvalidScene(f"payload '{name}': no attached object of that name (attached: {sorted(attached)})")
        if not (np.isfinite(mass) and mass >= 0):
            raise InvalidScene(f"payload '{name}': mass must be a finite number >= 0 kg, got {mass!r}")
    return dict(payloads)


def _add_robot_geoms(
    spec: mujoco.MjSpec, robot: RobotModel, bodies: list[mujoco.MjsBody], payloads: Mapping[str, float]
) -> dict[str, str]:
    """The collision geometry (attached objects included); each geom's name -> its link's or object's name.

    An attached object with a payload mass is a body of its own, welded to its link (its inertia from the geom)."""
    owners = {}
    for item in robot.collision_model.geometryObjects:
        attached = item.name.removeprefix("attached/") if item.name.startswith("attached/") else None
        body, pose = bodies[item.parentJoint], item.placement.homogeneous
        if attached is not None and payloads.get(attached, 0.0) > 0:
            body = body.add_body(name=f"payload/{attached}", pos=pose[:3, 3], quat=_quat(pose[:3, :3]))
            body.gravcomp, pose = 0.0, np.eye(4)
        geom = _add_geom(spec, body, item.name, item.geometry, pose)
        if attached is not None:
            geom.mass = payloads.get(attached, 0.0)
        geom.contype, geom.conaffinity = ROBOT_BITS
        geom.rgba = [0.7, 0.7, 0.75, 1.0]
        owners[item.name] = attached or robot.model.frames[item.parentFrame].name
    return owners


def _add_obstacles(spec: mujoco.MjSpec, scene: Scene | None) -> list[str]:
    if scene is None:
        return []
    for obstacle in scene.obstacles.values():
        geom = _add_geom(spec, spec.worldbody, OBSTACLE_PREFIX + obstacle.name, obstacle.geometry(), obstacle.pose)
        geom.contype, geom.conaffinity = OBSTACLE_BITS
        geom.rgba = [0.8, 0.4, 0.3, 1.0]
    return list(scene.obstacles)


def _add_geom(
    spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, shape: coal.CollisionGeometry, pose: np.ndarray
) -> mujoco.MjsGeom:
    """The coal ``shape`` at ``pose`` (4x4, in ``body``'s frame) as a MuJoCo geom."""
    geom = body.add_geom(name=name, pos=pose[:3, 3], quat=_quat(pose[:3, :3]))
    if isinstance(shape, coal.Box):
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_BOX, np.asarray(shape.halfSide, dtype=float)
    elif isinstance(shape, coal.Sphere):
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_SPHERE, [shape.radius, 0.0, 0.0]
    elif isinstance(shape, coal.Cylinder):
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_CYLINDER, [shape.radius, shape.halfLength, 0.0]
    elif isinstance(shape, coal.Capsule):
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_CAPSULE, [shape.radius, shape.halfLength, 0.0]
    elif hasattr(shape, "vertices") and hasattr(shape, "tri_indices"):
        mesh = spec.add_mesh(name=f"mesh/{name}")
        mesh.uservert = np.asarray(shape.vertices(), dtype=float).ravel()
        triangles = [shape.tri_indices(i) for i in range(shape.num_tris)]
        mesh.userface = np.array([[t[0], t[1], t[2]] for t in triangles], dtype=np.int32).ravel()
        geom.type, geom.meshname = mujoco.mjtGeom.mjGEOM_MESH, mesh.name
    else:
        raise InvalidScene(f"geometry '{name}': {type(shape).__name__} has no MuJoCo counterpart here")
    return geom


def _damping_gains(
    model: mujoco.MjModel, kp: np.ndarray, ratio: float, q0: np.ndarray, qpos_index: np.ndarray
) -> np.ndarray:
    """``kv = 2 ratio sqrt(kp M_ii(q0))``: the damping for ``ratio`` of each joint's own inertia at ``q0``
    (the armature included)."""
    data = mujoco.MjData(model)
    data.qpos[qpos_index] = np.clip(q0, model.jnt_range[qpos_index, 0], model.jnt_range[qpos_index, 1])
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    return np.asarray(2.0 * ratio * np.sqrt(kp * np.diag(full)[qpos_index]), dtype=float)


def _quat(rotation: np.ndarray) -> list[float]:
    """MuJoCo's ``[w, x, y, z]`` of a rotation matrix."""
    q = pin.Quaternion(np.asarray(rotation, dtype=float))
    return [float(q.w), float(q.x), float(q.y), float(q.z)]
