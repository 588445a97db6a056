"""A Jackal-like skid-steer base in MJCF: ~17 kg, chassis 0.508 x 0.430 m, four wheels with friction.

Each wheel is a hinge driven by a velocity servo whose torque (``forcerange``) and speed (``ctrlrange``)
are limited like the Jackal's motors. A ``/cmd_vel``-like twist (v, w) becomes wheel speeds as the
Jackal's ``diff_drive_controller`` computes them: a skid-steer base turns less than its wheel track
says, so the controller uses the track times ``wheel_separation_multiplier``.
Odometry (:class:`Odometry`) integrates the measured wheel speeds (forward speed) and a gyro with
noise and bias (yaw rate), as the Jackal's EKF does; it drifts. Ground truth is read from the model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maru_planner.physics.barn_world import WorldXml

ROBOT_GROUP = 2
WHEELS = ("front_left", "rear_left", "front_right", "rear_right")


@dataclass(frozen=True)
class JackalSpec:
    """Geometry, mass and motor limits of the Jackal-like base (Clearpath's published figures)."""

    chassis_length: float = 0.508  # m
    chassis_width: float = 0.430  # m
    chassis_height: float = 0.18  # m, from chassis_bottom up
    chassis_bottom: float = 0.07  # m above the floor
    chassis_mass: float = 13.0  # kg (with the 4 wheels: 17 kg)
    wheel_radius: float = 0.098  # m
    wheel_width: float = 0.04  # m
    wheel_mass: float = 1.0  # kg
    wheelbase: float = 0.262  # m between the axles
    track: float = 0.37559  # m between the wheel centres
    # jackal_control's diff_drive_controller uses 1.5 for Gazebo; MuJoCo's soft friction resists the skid more,
    # 4.0 makes the turn rate match the command within ~25 % from 0.5 to 2.5 rad/s (test_jackal_drive.py)
    wheel_separation_multiplier: float = 4.0
    wheel_friction: float = 0.6
    max_wheel_speed: float = 20.4  # rad/s (2.0 m/s)
    max_wheel_torque: float = 8.0  # N m per wheel
    servo_gain: float = 4.0  # N m per rad/s of speed error
    max_linear: float = 2.0  # m/s
    max_angular: float = 4.0  # rad/s
    gyro_noise: float = 0.005  # rad/s, white
    gyro_bias_sigma: float = 0.003  # rad/s, per-run constant bias
    wheel_noise: float = 0.01  # relative noise of the wheel encoders' speed

    @property
    def footprint(self) -> np.ndarray:
        hx, hy = self.chassis_length / 2, self.chassis_width / 2
        return np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])

    @property
    def circumradius(self) -> float:
        return math.hypot(self.chassis_length / 2, self.chassis_width / 2)


def jackal_xml(spec: JackalSpec, start: tuple[float, float, float]) -> WorldXml:
    """The base as an MJCF body (free joint at ``start`` = x, y, yaw) plus its four wheel actuators."""
    x, y, yaw = start
    half_z = spec.chassis_height / 2
    chassis_z = spec.chassis_bottom + half_z - spec.wheel_radius  # relative to the body frame at axle height
    wheels = []
    actuators = []
    for name in WHEELS:
        wx = spec.wheelbase / 2 if name.startswith("front") else -spec.wheelbase / 2
        wy = spec.track / 2 if name.endswith("left") else -spec.track / 2
        wheels.append(
            f'      <body name="{name}_wheel" pos="{wx} {wy} 0">\n'
            f'        <joint name="{name}" type="hinge" axis="0 1 0" damping="0.01"/>\n'
            f'        <geom name="{name}_tyre" type="cylinder" size="{spec.wheel_radius} {spec.wheel_width / 2}" '
            f'euler="90 0 0" mass="{spec.wheel_mass}" friction="{spec.wheel_friction} 0.005 0.0001" '
            f'group="{ROBOT_GROUP}" contype="1" conaffinity="1" condim="3" rgba="0.1 0.1 0.1 1"/>\n'
            f"      </body>"
        )
        actuators.append(
            f'    <velocity name="{name}_motor" joint="{name}" kv="{spec.servo_gain}" '
            f'ctrlrange="{-spec.max_wheel_speed} {spec.max_wheel_speed}" ctrllimited="true" '
            f'forcerange="{-spec.max_wheel_torque} {spec.max_wheel_torque}" forcelimited="true"/>'
        )
    qw, qz = math.cos(yaw / 2), math.sin(yaw / 2)
    body = (
        f'    <body name="base_link" pos="{x} {y} {spec.wheel_radius + 0.002}" quat="{qw} 0 0 {qz}">\n'
        '      <freejoint name="base"/>\n'
        f'      <geom name="chassis" type="box" size="{spec.chassis_length / 2} {spec.chassis_width / 2} {half_z}" '
        f'pos="0 0 {chassis_z}" mass="{spec.chassis_mass}" group="{ROBOT_GROUP}" contype="1" conaffinity="1" '
        'rgba="0.9 0.8 0.1 1"/>\n' + "\n".join(wheels) + "\n    </body>"
    )
    return WorldXml(robot_body=body, actuators="\n".join(actuators))


def wheel_speeds(spec: JackalSpec, v: float, w: float) -> np.ndarray:
    """(v, w) clipped to the limits -> wheel speeds (rad/s) in ``WHEELS`` order, scaled down together at saturation."""
    v = float(np.clip(v, -spec.max_linear, spec.max_linear))
    w = float(np.clip(w, -spec.max_angular, spec.max_angular))
    half_track = spec.track * spec.wheel_separation_multiplier / 2
    left, right = (v - w * half_track) / spec.wheel_radius, (v + w * half_track) / spec.wheel_radius
    peak = max(abs(left), abs(right))
    if peak > spec.max_wheel_speed:
        left, right = left * spec.max_wheel_speed / peak, right * spec.max_wheel_speed / peak
    return np.array([left, left, right, right])


class Odometry:
    """Dead reckoning in the odom frame (identity at the start): wheel encoders for v, a biased noisy gyro for w."""

    def __init__(self, spec: JackalSpec, rng: np.random.Generator):
        self.spec = spec
        self.rng = rng
        self.bias = float(rng.normal(0.0, spec.gyro_bias_sigma))
        self.pose = np.zeros(3)  # x, y, yaw
        self.twist = np.zeros(2)  # v, w
        self._encoder_scale = np.zeros((0, 4))  # per step: 1 + encoder noise, one row per wheel set
        self._gyro_noise: list[float] = []
        self._cursor = 0

    def update(self, wheel_rates: np.ndarray, true_yaw_rate: float, dt: float) -> None:
        spec = self.spec
        if self._cursor >= len(self._gyro_noise):
            self._draw_noise()
        scale, gyro = self._encoder_scale[self._cursor], self._gyro_noise[self._cursor]
        self._cursor += 1
        v = spec.wheel_radius * float(wheel_rates @ scale) / 4.0
        w = true_yaw_rate + self.bias + gyro
        x, y, yaw = self.pose.tolist()
        mid = yaw + 0.5 * w * dt
        yaw += w * dt
        self.pose[:] = (
            x + v * math.cos(mid) * dt,
            y + v * math.sin(mid) * dt,
            math.atan2(math.sin(yaw), math.cos(yaw)),
        )
        self.twist[:] = (v, w)

    def _draw_noise(self) -> None:
        """Five standard normals per step (4 encoders, the gyro), drawn and scaled in blocks (per step is slow)."""
        noise = self.rng.normal(size=(1000, 5))
        self._encoder_scale = 1.0 + self.spec.wheel_noise * noise[:, :4]
        self._gyro_noise = (self.spec.gyro_noise * noise[:, 4]).tolist()
        self._cursor = 0
