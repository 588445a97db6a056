"""RobotModel: URDF + SRDF -> Pinocchio model, collision geometry, planning groups, FK.

Robots known by name (Maru-1, the example-robot-data arms) load through their profile
(``RobotModel.from_profile``; the table is ``maru_planner/robot/robot_profile.py``'s, which
``maru_planner/robot/profiles.py`` fills from ``maru_planner/robot/robots/*.yaml``), a user's robot through its
profile file (``RobotModel.from_profile("my_arm.yaml")``, docs/your_robot.md); any other URDF through ``from_urdf``.

Any URDF loads with a fixed base. Joints whose configuration is not one
number (continuous wheels, spherical, planar...) and any joints named in
``locked_joints`` are locked (Pinocchio reduced model), so for every robot
``nq == nv`` and q[i] is joint ``joint_names[i]``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from maru_planner.errors import InvalidGroup, InvalidRequest
from maru_planner.robot import profile_yaml, robot_profile
from maru_planner.robot.ik_strategy import IKStrategy
from maru_planner.robot.robot_profile import DEFAULT_ACCELERATION_LIMIT, InvalidRobotProfile, RobotProfile
from maru_planner.robot.sphere_options import SphereFitOptions
from maru_planner.robot.srdf import SrdfInfo, parse_srdf

WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class RobotModel:
    """A fixed-base robot for planning: kinematics, limits, groups, collision geometry."""

    def __init__(
        self,
        name: str,
        model: pin.Model,
        collision_model: pin.GeometryModel,
        srdf: SrdfInfo | None = None,
        *,
        acceleration_limits: float | Sequence[float] = DEFAULT_ACCELERATION_LIMIT,
        end_effectors: Mapping[str, str] | None = None,
        ik_strategies: Sequence[IKStrategy] = (),
    ):
        """``ik_strategies``: robot-specific IK tried before the numeric one (``robot.ik.solve_ik``)."""
        if model.nq != model.nv:
            raise ValueError(f"{name}: nq ({model.nq}) != nv ({model.nv}); lock multi-dof joints first")
        self.name = name
        self.model = model
        self.data = model.createData()
        self.collision_model = collision_model
        self.srdf = srdf or SrdfInfo()
        # Without SRDF collision info, parent/child links are never checked against each other.
        self.skip_adjacent_pairs = not self.srdf.disabled_pairs
        self.joint_names: list[str] = [model.names[j] for j in range(1, model.njoints)]
        self.nq = model.nq
        self._joint_q_index = {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints)}
        self.lower_limits = np.array(model.lowerPositionLimit, dtype=float)
        self.upper_limits = np.array(model.upperPositionLimit, dtype=float)
        self.velocity_limits = np.array(model.velocityLimit, dtype=float)
        self.acceleration_limits = np.broadcast_to(np.asarray(acceleration_limits, dtype=float), (self.nq,)).copy()
        self.groups = self._make_groups()
        self.named_states = dict(self.srdf.group_states)
        ee = dict(end_effectors) if end_effectors is not None else dict(self.srdf.end_effectors)
        self.end_effectors = {k: v for k, v in ee.items() if model.existFrame(v)} or self._default_end_effector()
        self.ik_strategies: tuple[IKStrategy, ...] = tuple(ik_strategies)
        self.sphere_options = SphereFitOptions()  # how its sphere model is fitted (a profile's ``sphere_model``)
        self._frame_ids: dict[str, int] = {}

    # ------------------------------------------------------------ loading --
    @classmethod
    def from_urdf(
        cls,
        urdf_path: str | Path,
        srdf_path: str | Path | None = None,
        package_dirs: Sequence[str | Path] | None = None,
        *,
        name: str | None = None,
        locked_joints: Mapping[str, float] | None = None,
        acceleration_limits: float | Sequence[float] = DEFAULT_ACCELERATION_LIMIT,
        end_effectors: Mapping[str, str] | None = None,
        ik_strategies: Sequence[IKStrategy] | None = None,
    ) -> RobotModel:
        """Load any robot; ``locked_joints`` maps joint names to the value they are frozen at.

        ``ik_strategies`` None: those of the profile whose ``urdf_name`` is the URDF's robot name, if any (whose
        ``sphere_model`` options the robot takes too).
        """
        urdf_path = Path(urdf_path)
        if not urdf_path.is_file():
            raise FileNotFoundError(f"URDF not found: {urdf_path}")
        dirs = [str(p) for p in (package_dirs or [])]
        model = pin.buildModelFromUrdf(str(urdf_path))
        geom = pin.buildGeomFromUrdf(model, str(urdf_path), pin.COLLISION, package_dirs=dirs)
        model, geom = _lock_joints(model, geom, dict(locked_joints or {}))
        srdf = None
        if srdf_path is not None:
            srdf = parse_srdf(Path(srdf_path), lambda base, tip: _chain_joints(model, base, tip))
            known = set(model.names)
            srdf.groups = {g: [j for j in js if j in known] for g, js in srdf.groups.items()}
            srdf.groups = {g: js for g, js in srdf.groups.items() if js}
        matching = robot_profile.profile_for_urdf(model.name)
        if ik_strategies is None:
            ik_strategies = matching.ik_strategies if matching is not None else ()
        loaded = cls(
            name or model.name,
            model,
            geom,
            srdf,
            acceleration_limits=acceleration_limits,
            end_effectors=end_effectors,
            ik_strategies=ik_strategies,
        )
        if matching is not None:  # a built-in robot's URDF loaded by path fits its spheres as its profile says
            loaded.sphere_options = matching.sphere_model
        return loaded

    @classmethod
    def from_profile(cls, robot: str | Path | RobotProfile) -> RobotModel:
        """A robot by profile: a built-in name (``maru_planner/robot/profiles.py``), a profile YAML file
        (``.yaml``/``.yml``, :mod:`maru_planner.robot.profile_yaml`) or a :class:`RobotProfile`.

        InvalidRobotProfile when the profile does not fit its URDF (limits, groups, end effectors, locks)."""
        profile = profile_yaml.resolve(robot)
        files = profile.files()
        try:
            loaded = cls.from_urdf(
                files.urdf,
                files.srdf,
                package_dirs=files.package_dirs,
                name=profile.name,
                locked_joints=profile.locked_joints,
                end_effectors=profile.end_effectors or None,
                ik_strategies=profile.ik_strategies,
            )
        except InvalidRequest as exc:  # the only one from_urdf raises: a lock of an unknown joint
            raise InvalidRobotProfile(f"robot {profile.name}: locked_joints: {exc}") from None
        loaded._apply_profile(profile)
        return loaded

    def _apply_profile(self, profile: RobotProfile) -> None:
        """The profile's limits, groups (checked) and collision rule; its end effectors must be frames of the robot."""
        limits = np.asarray(profile.acceleration_limits, dtype=float)
        if limits.ndim == 1 and len(limits) != self.nq:
            raise InvalidRobotProfile(
                f"robot {profile.name}: acceleration_limits: {len(limits)} values for the {self.nq} joints "
                f"{self.joint_names}"
            )
        self.acceleration_limits = np.broadcast_to(limits, (self.nq,)).copy()
        for group, joints in profile.groups.items():
            unknown = [j for j in joints if j not in self._joint_q_index]
            if unknown:
                raise InvalidRobotProfile(
                    f"robot {profile.name}: groups: {group}: unknown joint(s) {unknown}; joints: {self.joint_names}"
                )
        self.groups = {**self.groups, **{g: list(js) for g, js in profile.groups.items()}}
        missing = {k: v for k, v in profile.end_effectors.items() if not self.model.existFrame(v)}
        if missing:
            raise InvalidRobotProfile(f"robot {profile.name}: end_effectors: no such frame(s) {missing}")
        if profile.ignore_links_touching_at_rest:
            self.disable_default_collisions()
        self.sphere_options = profile.sphere_model

    @classmethod
    def maru1(cls) -> RobotModel:
        """The Maru-1 13-DOF upper body (urdf/maru1_upper_body.urdf + .srdf)."""
        return cls.from_profile("maru1")

    # ------------------------------------------------------------- groups --
    def _make_groups(self) -> dict[str, list[str]]:
        if self.srdf.groups:
            return {g: list(js) for g, js in self.srdf.groups.items()}
        return {"all": list(self.joint_names)}

    def group_joint_indices(self, group: str | None) -> np.ndarray:
        """Indices into q of the group's joints (all joints for ``None``)."""
        if group is None:
            return np.arange(self.nq)
        if group not in self.groups:
            raise InvalidGroup(f"unknown planning group {group!r} for {self.name}; known: {sorted(self.groups)}")
        return np.array([self._joint_q_index[j] for j in self.groups[group]], dtype=int)

    def joint_indices(self, names: Sequence[str]) -> np.ndarray:
        """Indices into q of named joints; raises InvalidRequest for an unknown name."""
        missing = [n for n in names if n not in self._joint_q_index]
        if missing:
            raise InvalidRequest(f"unknown joint(s) {missing} for {self.name}")
        return np.array([self._joint_q_index[n] for n in names], dtype=int)

    def _default_end_effector(self) -> dict[str, str]:
        """The body frame of the last joint's deepest child link."""
        last_joint = self.model.njoints - 1
        bodies = [f for f in self.model.frames if f.parentJoint == last_joint and f.type == pin.FrameType.BODY]
        return {"tip": bodies[-1].name} if bodies else {}

    def disable_default_collisions(self, q: np.ndarray | None = None) -> list[tuple[str, str]]:
        """Add the link pairs colliding at ``q`` (default: neutral) to the disabled pairs.

        MoveIt's "Default" rule, for robots shipped without an SRDF whose
        links touch in their rest posture (e.g. TIAGo's arm mount). Returns the
        pairs added (pairs on one rigid body or parent/child are never checked anyway).
        Build CollisionCheckers after calling this.
        """
        q = self.neutral() if q is None else np.asarray(q, dtype=float)
        geom = self.collision_model.copy()
        geom.addAllCollisionPairs()
        geom_data = pin.GeometryData(geom)
        for request in geom_data.collisionRequests:
            request.enable_contact = False
        pin.computeCollisions(self.model, self.model.createData(), geom, geom_data, q, False)
        links = [self.model.frames[g.parentFrame].name for g in geom.geometryObjects]
        pairs = []
        for pair, result in zip(geom.collisionPairs, geom_data.collisionResults):
            a, b = links[pair.first], links[pair.second]
            if result.isCollision() and a != b and (a, b) not in pairs and (b, a) not in pairs:
                pairs.append((a, b))
        self.srdf.disabled_pairs.update(frozenset(p) for p in pairs)
        return pairs

    # ----------------------------------------------------------- configs --
    def neutral(self) -> np.ndarray:
        """Zeros clipped into the joint limits."""
        return np.clip(np.zeros(self.nq), self.lower_limits, self.upper_limits)

    def named_state(self, name: str) -> np.ndarray:
        """A configuration from an SRDF group_state, other joints at neutral()."""
        if name not in self.named_states:
            raise InvalidRequest(f"unknown named state {name!r}; known: {sorted(self.named_states)}")
        q = self.neutral()
        for joint, value in self.named_states[name].items():
            if joint in self._joint_q_index:
                q[self._joint_q_index[joint]] = value
        return q

    def within_limits(self, q: np.ndarray, tol: float = 1e-9) -> bool:
        return bool(np.all(q >= self.lower_limits - tol) and np.all(q <= self.upper_limits + tol))

    def random_configuration(self, rng: np.random.Generator | None = None) -> np.ndarray:
        """Uniform in the limits (paper 000 eq. 25)."""
        rng = rng or np.random.default_rng()
        return rng.uniform(self.lower_limits, self.upper_limits)

    # -------------------------------------------------------- kinematics --
    def frame_id(self, frame: str) -> int:
        fid = self._frame_ids.get(frame)
        if fid is None:
            if not self.model.existFrame(frame):
                raise InvalidRequest(f"unknown frame {frame!r} for {self.name}")
            fid = self._frame_ids[frame] = self.model.getFrameId(frame)
        return fid

    def frame_placement(self, q: np.ndarray, frame: str | int) -> pin.SE3:
        """Pose of a frame in the root frame as a pinocchio SE3 (shares self.data)."""
        fid = frame if isinstance(frame, int) else self.frame_id(frame)
        pin.forwardKinematics(self.model, self.data, q)
        return pin.updateFramePlacement(self.model, self.data, fid)

    def frame_pose(self, q: np.ndarray, frame: str | int) -> np.ndarray:
        """4x4 pose of a frame in the root frame (base_link / world)."""
        return self.frame_placement(q, frame).homogeneous

    def frame_jacobian(self, q: np.ndarray, frame: str | int) -> np.ndarray:
        """6 x nv Jacobian (linear; angular) of a frame, LOCAL_WORLD_ALIGNED."""
        fid = frame if isinstance(frame, int) else self.frame_id(frame)
        return pin.computeFrameJacobian(self.model, self.data, q, fid, WORLD)

    def __repr__(self) -> str:
        return f"RobotModel({self.name!r}, nq={self.nq}, groups={list(self.groups)})"


def _lock_joints(
    model: pin.Model, geom: pin.GeometryModel, locked: dict[str, float]
) -> tuple[pin.Model, pin.GeometryModel]:
    unknown = [n for n in locked if not model.existJointName(n)]
    if unknown:
        raise InvalidRequest(f"cannot lock unknown joint(s) {unknown}")
    q_ref = pin.neutral(model)
    lock_ids = []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        jname = model.names[j]
        if jname in locked:
            q_ref[joint.idx_q] = locked[jname]
            lock_ids.append(j)
        elif joint.nq != 1 or joint.nv != 1:
            lock_ids.append(j)
    if not lock_ids:
        return model, geom
    reduced, (reduced_geom,) = pin.buildReducedModel(model, [geom], lock_ids, q_ref)
    return reduced, reduced_geom


def _chain_joints(model: pin.Model, base_link: str, tip_link: str) -> list[str]:
    """Joint names from base_link (exclusive) to tip_link (inclusive), root first."""
    if not (model.existFrame(base_link) and model.existFrame(tip_link)):
        return []
    base_joint = model.frames[model.getFrameId(base_link)].parentJoint
    j = model.frames[model.getFrameId(tip_link)].parentJoint
    chain = []
    while j != base_joint and j != 0:
        chain.append(model.names[j])
        j = model.parents[j]
    return chain[::-1]


def load_example_robot(name: str) -> RobotModel:
    """A robot of the profile table by name: 'panda', 'ur5', 'tiago', 'talos' (or 'maru1')."""
    return RobotModel.from_profile(name)
