"""Stepping a simulated arm (:mod:`maru_planner.physics.arm_model`): servo set-points in, joint state out,
robot-obstacle contacts with their penetration depth and the steps an effort limit was reached.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from maru_planner.errors import InvalidJointCount, InvalidState
from maru_planner.physics.arm_model import ArmModel

SATURATION_FRACTION = 0.999  # |tau| >= this fraction of the effort limit counts as saturated


@dataclass(frozen=True)
class JointState:
    """Positions, velocities and actuator efforts in the arm's joint order, at simulated ``time`` (s)."""

    time: float
    positions: np.ndarray
    velocities: np.ndarray
    efforts: np.ndarray


@dataclass(frozen=True)
class Contact:
    """A robot-obstacle contact: the robot's link (or attached object), the obstacle, penetration depth (m)."""

    link: str
    obstacle: str
    depth: float
    time: float


@dataclass
class ContactLog:
    """The deepest penetration seen per (link, obstacle) pair, and how many steps had any contact."""

    deepest: dict[tuple[str, str], Contact] = field(default_factory=dict)
    steps_in_contact: int = 0

    def add(self, contacts: list[Contact]) -> None:
        if contacts:
            self.steps_in_contact += 1
        for contact in contacts:
            key = (contact.link, contact.obstacle)
            if key not in self.deepest or contact.depth > self.deepest[key].depth:
                self.deepest[key] = contact

    @property
    def max_depth(self) -> float:
        return max((c.depth for c in self.deepest.values()), default=0.0)


class ArmSim:
    """One simulated arm: ``reset``, ``command`` (position and velocity set-points), ``step``, ``state``."""

    def __init__(self, arm: ArmModel):
        self.arm = arm
        self.data = mujoco.MjData(arm.model)
        self.contacts = ContactLog()
        self.saturated_steps = 0
        self._n = arm.nq

    @property
    def time(self) -> float:
        return float(self.data.time)

    @property
    def timestep(self) -> float:
        return float(self.arm.model.opt.timestep)

    def reset(self, positions: np.ndarray) -> None:
        """At rest at ``positions`` (all joints), holding them; time, contacts and saturation counts zeroed."""
        q = self._checked(positions, "positions")
        mujoco.mj_resetData(self.arm.model, self.data)
        self.data.qpos[self.arm.qpos_index] = q
        self.command(q, np.zeros(self._n))
        mujoco.mj_forward(self.arm.model, self.data)  # qM at q: for the feedforward of the first command
        self.contacts = ContactLog()
        self.saturated_steps = 0

    def command(self, positions: np.ndarray, velocities: np.ndarray, accelerations: np.ndarray | None = None) -> None:
        """The servo set-points of every joint (the arm's joint order); ``accelerations`` feed forward ``M(q) a``
        (when the arm's servo has it; None: zero)."""
        n = self._n
        self.data.ctrl[:n] = positions
        self.data.ctrl[n : 2 * n] = velocities
        self.data.ctrl[2 * n :] = 0.0
        if accelerations is not None and self.arm.acceleration_feedforward:
            self.data.ctrl[2 * n :] = self.inertia_torques(accelerations)

    def inertia_torques(self, accelerations: np.ndarray) -> np.ndarray:
        """``M(q) a``: the joint torques that give the arm ``accelerations`` (its inertia at the current state)."""
        wanted = np.zeros(self.arm.model.nv)
        wanted[self.arm.qpos_index] = accelerations
        torques = np.zeros(self.arm.model.nv)
        mujoco.mj_mulM(self.arm.model, self.data, torques, wanted)
        return torques[self.arm.qpos_index]

    def step(self, steps: int = 1) -> list[Contact]:
        """Advance ``steps`` physics steps; the contacts of the last one (also logged in :attr:`contacts`)."""
        contacts: list[Contact] = []
        for _ in range(steps):
            mujoco.mj_step(self.arm.model, self.data)
            efforts = self.data.qfrc_actuator[self.arm.qpos_index]
            if np.any(np.abs(efforts) >= SATURATION_FRACTION * self.arm.effort_limits):
                self.saturated_steps += 1
            contacts = self.current_contacts() if self.data.ncon else []
            self.contacts.add(contacts)
        return contacts

    def state(self) -> JointState:
        index = self.arm.qpos_index
        return JointState(
            self.time,
            self.data.qpos[index].copy(),
            self.data.qvel[index].copy(),
            self.data.qfrc_actuator[index].copy(),
        )

    def current_contacts(self) -> list[Contact]:
        """Robot-obstacle contacts now; ``depth`` is MuJoCo's penetration (-dist, 0 when only touching)."""
        out = []
        for k in range(self.data.ncon):
            contact = self.data.contact[k]
            g1, g2 = int(contact.geom1), int(contact.geom2)
            if self.arm.is_obstacle(g1):
                g1, g2 = g2, g1
            if not self.arm.is_obstacle(g2) or contact.dist > 0:
                continue
            out.append(Contact(self.arm.geom_owner(g1), self.arm.geom_owner(g2), float(-contact.dist), self.time))
        return out

    def _checked(self, values: np.ndarray, what: str) -> np.ndarray:
        array = np.asarray(values, dtype=float)
        if array.shape != (self._n,):
            raise InvalidJointCount(f"{what}: expected {self._n} values (one per joint), got shape {array.shape}")
        if not np.all(np.isfinite(array)):
            raise InvalidState(
                f"{what}: NaN or infinite value at joint {self.arm.joint_names[int(np.argmin(np.isfinite(array)))]}"
            )
        return array
