"""One stepping loop for a base in a BARN world: physics at a fixed dt, the laser at its rate, contacts, odometry.

``BaseSim`` owns the MuJoCo model of one world with the Jackal-like base. A caller sets a twist with
:meth:`command` (``/cmd_vel``) and advances the clock; the simulation keeps the latest scan, the
odometry (drifting) and the ground truth apart, and records every contact between the robot and an
obstacle (the challenge's collision). A command that is not finite stops the robot (and is counted);
a command older than ``cmd_timeout`` stops it too (the run can say so from :attr:`events`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from maru_planner.physics.barn_world import CYLINDER_RADIUS, OBSTACLE_GROUP, START, cylinder_centres, world_mjcf
from maru_planner.physics.jackal import WHEELS, JackalSpec, Odometry, jackal_xml, wheel_speeds
from maru_planner.physics.laser import Laser, LaserSpec, Scan


@dataclass
class SimEvents:
    """What went wrong on the command side: non-finite commands and command timeouts (counts, first times)."""

    nan_commands: int = 0
    cmd_timeouts: int = 0
    first_timeout_s: float | None = None
    contacts: list[tuple[float, float, float]] = field(default_factory=list)  # (t, x, y) of each new contact


class BaseSim:
    """A BARN world (30 x 30 grid) with the base at ``start``; ``seed`` drives the laser and odometry noise."""

    def __init__(
        self,
        grid: np.ndarray,
        seed: int = 0,
        jackal: JackalSpec | None = None,
        laser: LaserSpec | None = None,
        timestep: float = 0.005,
        cmd_timeout: float = 0.5,
        start: tuple[float, float, float] = START,
        scan_on_demand: bool = False,
    ):
        self.jackal = jackal or JackalSpec()
        self.laser_spec = laser or LaserSpec()
        self.timestep = timestep
        self.cmd_timeout = cmd_timeout
        # True: a laser tick casts only if it is the last one of an advance() (nobody reads the others)
        self.scan_on_demand = scan_on_demand
        self._scan_until = math.inf
        self.start = start
        self.rng = np.random.default_rng(seed)
        xml = world_mjcf(grid, jackal_xml(self.jackal, start), timestep)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.obstacles = cylinder_centres(grid)
        self._laser = Laser(self.laser_spec, OBSTACLE_GROUP, self.rng)
        self.odometry = Odometry(self.jackal, self.rng)
        self._wheel_dofs = np.array([self.model.jnt_dofadr[self.model.joint(n).id] for n in WHEELS])
        base = self.model.body("base_link").id
        robot_geom = np.isin(self.model.geom_bodyid, [base, *(self.model.body(f"{n}_wheel").id for n in WHEELS)])
        # per geom: 1 robot, 2 obstacle, 0 other; a contact pair's product is 2 only for robot against obstacle
        self._geom_kind = robot_geom.astype(np.int8) + 2 * (self.model.geom_group == OBSTACLE_GROUP).astype(np.int8)
        self.events = SimEvents()
        self.time = 0.0
        self._cmd = (0.0, 0.0)
        self._applied = (0.0, 0.0)
        self._last_cmd_time = -math.inf
        self._timed_out = False
        self._in_contact = False
        self._next_scan = 0.0
        self.latest_scan: Scan | None = None
        self.scans = 0

    # -- inputs --------------------------------------------------------------------------------------
    def command(self, v: float, w: float) -> None:
        """A /cmd_vel twist; NaN or inf stops the robot and is counted in ``events.nan_commands``."""
        if not (math.isfinite(v) and math.isfinite(w)):
            self.events.nan_commands += 1
            self._cmd = (0.0, 0.0)
        else:
            self._cmd = (float(v), float(w))
        self._last_cmd_time = self.time
        self._timed_out = False

    # -- state ---------------------------------------------------------------------------------------
    def true_pose(self) -> tuple[float, float, float]:
        """Ground truth (x, y, yaw) of base_link in the world."""
        q = self.data.qpos
        w, x, y, z = q[3:7]
        return float(q[0]), float(q[1]), math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))

    def true_twist(self) -> tuple[float, float]:
        """Ground-truth forward speed and yaw rate."""
        x, y, yaw = self.true_pose()
        vx, vy = self.data.qvel[0], self.data.qvel[1]
        return float(math.cos(yaw) * vx + math.sin(yaw) * vy), float(self.data.qvel[5])

    @property
    def in_contact(self) -> bool:
        return self._in_contact

    @property
    def collided(self) -> bool:
        return bool(self.events.contacts)

    def clearance(self) -> float:
        """Distance from the chassis rectangle (true pose) to the nearest cylinder surface (< 0: overlap)."""
        x, y, yaw = self.true_pose()
        rel = self.obstacles - (x, y)
        near = rel[np.einsum("ij,ij->i", rel, rel) < 4.0]
        if len(near) == 0:
            return math.inf
        c, s = math.cos(yaw), math.sin(yaw)
        local = np.column_stack([c * near[:, 0] + s * near[:, 1], -s * near[:, 0] + c * near[:, 1]])
        half = np.array([self.jackal.chassis_length / 2, self.jackal.chassis_width / 2])
        outside = np.maximum(np.abs(local) - half, 0.0)
        inside = np.minimum(np.max(np.abs(local) - half, axis=1), 0.0)
        return float(np.min(np.hypot(outside[:, 0], outside[:, 1]) + inside) - CYLINDER_RADIUS)

    # -- stepping ------------------------------------------------------------------------------------
    def step(self) -> None:
        """One physics step: command timeout, wheel servos, dynamics, odometry, contacts, the laser when due."""
        if not self._timed_out and self.time - self._last_cmd_time > self.cmd_timeout:
            self._timed_out = True
            if self._cmd != (0.0, 0.0) or self._last_cmd_time > -math.inf:
                self.events.cmd_timeouts += 1
                if self.events.first_timeout_s is None:
                    self.events.first_timeout_s = round(self.time, 4)
            self._cmd = (0.0, 0.0)
        if self._cmd != self._applied:
            self.data.ctrl[:] = wheel_speeds(self.jackal, *self._cmd)
            self._applied = self._cmd
        mujoco.mj_step(self.model, self.data)
        self.time += self.timestep
        qvel = self.data.qvel
        self.odometry.update(qvel[self._wheel_dofs], float(qvel[5]), self.timestep)
        self._check_contacts()
        if self.time + 1e-9 >= self._next_scan:
            period = 1.0 / self.laser_spec.rate
            if not self.scan_on_demand or self._next_scan + period > self._scan_until + 1e-9:
                self.latest_scan = self._laser.scan(self.model, self.data, self.true_pose(), self.time)
                self.scans += 1
            self._next_scan += period

    def advance(self, duration: float) -> None:
        """Step the physics for ``duration`` seconds (rounded to whole steps)."""
        steps = max(1, round(duration / self.timestep))
        self._scan_until = self.time + steps * self.timestep
        for _ in range(steps):
            self.step()

    def _check_contacts(self) -> None:
        touching = False
        if self.data.ncon:
            kinds = self._geom_kind[self.data.contact.geom]
            touching = bool((kinds[:, 0] * kinds[:, 1] == 2).any())
        if touching and not self._in_contact:
            x, y, _ = self.true_pose()
            self.events.contacts.append((round(self.time, 4), x, y))
        self._in_contact = touching
