"""mujoco_sim_node: a BARN world in MuJoCo with the Jackal-like base, as a simulator node (issue 38).

Publishes ``/clock`` (rosgraph_msgs/Clock, sim time), ``scan`` (sensor_msgs/LaserScan, the UST-10-like laser),
``odom`` (nav_msgs/Odometry from the simulated wheels: it drifts), odom -> base_link on ``/tf``, the ground
truth on ``~/ground_truth`` (world frame, for scoring and pictures only) and one JSON line per step on
``~/status`` (sim time, truth, contacts, command timeouts, non-finite commands); subscribes ``cmd_vel``.

Two ways to step (``lockstep``):

- lock-step (default): the node publishes the state, waits for the next ``cmd_vel`` and then advances
  ``control_period`` of sim time: deterministic for a fixed ``seed`` and as fast as the controller answers.
  Until the first command the state is re-published every ``lockstep_wait`` s (wall) without advancing, for
  subscribers that join late; with ``first_state_subscribers`` the first state is held until that many
  subscriptions of ``scan``, ``odom`` and ``~/status`` have matched (a state published before discovery is
  lost, and waiting for the re-publish cost a whole ``lockstep_wait``). After the first command, a controller
  silent for ``lockstep_wait`` s no longer holds the clock: the node advances on its own, and the base stops
  ``cmd_timeout`` s (sim) after the last command (counted in ``~/status`` and logged), as a real base's
  command watchdog would.
- real time: the physics advances ``1 / laser rate`` per tick of a wall timer at ``real_time_factor``, and
  ``cmd_vel`` sets the command whenever it arrives.

A non-finite ``cmd_vel`` stops the robot (counted, warned); the node keeps serving. A managed node
(:mod:`maru_planner.ros.lifecycle`): configure builds the world (``world`` or ``grid_file``), activate starts
the stepping, deactivate stops it (the sim keeps its state). Parameters: :class:`MujocoSimConfig`
(``config/mujoco_sim.yaml``).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from typing import Any

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.timer import Timer
from rosgraph_msgs.msg import Clock  # type: ignore[import-untyped]
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage  # type: ignore[import-untyped]

from maru_planner.errors import InvalidRequest
from maru_planner.params import dataclass_params, param
from maru_planner.physics.barn_world import WORLD_COUNT, load_grid, world_grid
from maru_planner.physics.base_sim import BaseSim
from maru_planner.ros import mujoco_sim_conversions as conv
from maru_planner.ros import parameters
from maru_planner.ros.lifecycle import ManagedNode, run_node


@dataclasses.dataclass
class MujocoSimConfig:
    """mujoco_sim_node's parameters."""

    world: int = param(0, "public BARN world (0..299), used when grid_file is empty", lower=0,
                       upper=WORLD_COUNT - 1, read_only=True)  # fmt: skip
    grid_file: str = param("", "a 30 x 30 uint8 .npy grid (1 = cylinder) instead of a public world",
                           read_only=True)  # fmt: skip
    seed: int = param(0, "laser and odometry noise seed", lower=0, read_only=True)
    lockstep: bool = param(True, "advance control_period per cmd_vel (deterministic); false: real time",
                           read_only=True)  # fmt: skip
    control_period: float = param(0.1, "sim s advanced per cmd_vel in lock-step", lower=0.005, upper=1.0,
                                  read_only=True)  # fmt: skip
    lockstep_wait: float = param(1.0, "wall s without a cmd_vel after which lock-step advances on its own",
                                 lower=0.01, upper=60.0)  # fmt: skip
    first_state_subscribers: int = param(0, "lock-step: hold the first state until scan, odom and ~/status "
                                         "together have this many matched subscriptions (at most lockstep_wait)",
                                         lower=0, upper=1000, read_only=True)  # fmt: skip
    real_time_factor: float = param(1.0, "sim s per wall s when not in lock-step", lower=0.01, upper=100.0)
    cmd_timeout: float = param(0.5, "sim s after the last cmd_vel at which the base stops", lower=0.01,
                               upper=10.0, read_only=True)  # fmt: skip
    world_frame: str = param("world", "frame of ~/ground_truth", read_only=True)
    odom_frame: str = param("odom", "frame of odom and the parent on /tf", read_only=True)
    base_frame: str = param("base_link", "the robot's frame", read_only=True)
    laser_frame: str = param("base_laser", "frame_id of scan", read_only=True)
    publish_tf: bool = param(True, "publish odom -> base_link on /tf", read_only=True)


SPECS = dataclass_params(MujocoSimConfig)
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


class MujocoSimNode(ManagedNode):
    def __init__(self, **kwargs: Any):
        super().__init__("mujoco_sim_node", **kwargs)
        self.config = MujocoSimConfig(**parameters.declare_parameters(self, SPECS))
        parameters.add_on_set_parameters_callback(self, SPECS, self.when_configured(self._apply))
        self.sim: BaseSim | None = None
        self._timer: Timer | None = None
        self.steps = 0
        self.silent_steps = 0  # lock-step periods advanced without a command (a silent controller)
        self._commanded = False  # a cmd_vel has arrived since activation
        self._last_publish = 0.0  # wall time of the last state published
        self._published = False  # a state has been published since activation
        self.start()

    def _apply(self, changes: dict[str, Any]) -> None:
        self.config = dataclasses.replace(self.config, **changes)

    # ------------------------------------------------------------------------------------------ lifecycle --
    def configure(self) -> None:
        c = self.config
        grid = load_grid(c.grid_file) if c.grid_file else world_grid(c.world)
        self.sim = BaseSim(grid, seed=c.seed, cmd_timeout=c.cmd_timeout, scan_on_demand=c.lockstep)
        if c.control_period < self.sim.timestep:
            raise InvalidRequest(f"control_period {c.control_period} is below the physics step {self.sim.timestep}")
        self.clock_pub = self.create_lifecycle_publisher(Clock, "/clock", 10)
        self.scan_pub = self.create_lifecycle_publisher(LaserScan, "scan", RELIABLE)
        self.odom_pub = self.create_lifecycle_publisher(Odometry, "odom", RELIABLE)
        self.truth_pub = self.create_lifecycle_publisher(Odometry, "~/ground_truth", 10)
        self.status_pub = self.create_lifecycle_publisher(String, "~/status", RELIABLE)
        self.tf_pub = self.create_lifecycle_publisher(TFMessage, "/tf", 100) if c.publish_tf else None
        self.create_subscription(Twist, "cmd_vel", self._on_cmd_vel, RELIABLE)
        source = c.grid_file or f"world {c.world}"
        self.get_logger().info(
            f"{source}: {len(self.sim.obstacles)} cylinders, seed {c.seed}, "
            + (f"lock-step {c.control_period} s per cmd_vel" if c.lockstep else f"real time x{c.real_time_factor}")
        )

    def activate(self) -> None:
        assert self.sim is not None
        self._commanded = self._published = False
        if self.sim.latest_scan is None:
            self.sim.advance(self.config.control_period if self.config.lockstep else self._tick())
        if self.config.lockstep:
            self._timer = self.create_timer(min(0.05, self.config.lockstep_wait / 2), self._lockstep_watch)
            self._last_publish = time.monotonic()
            if self._subscribers_matched():
                self._publish()
        else:
            self._timer = self.create_timer(self._tick() / self.config.real_time_factor, self._real_time_step)

    def deactivate(self) -> None:
        if self._timer is not None:
            self.destroy_timer(self._timer)
            self._timer = None

    def cleanup(self) -> None:
        self.sim = None

    def _subscribers_matched(self) -> bool:
        matched = sum(pub.get_subscription_count() for pub in (self.scan_pub, self.odom_pub, self.status_pub))
        return matched >= self.config.first_state_subscribers

    def _tick(self) -> float:
        assert self.sim is not None
        return 1.0 / self.sim.laser_spec.rate

    # --------------------------------------------------------------------------------------------- inputs --
    def _on_cmd_vel(self, msg: Twist) -> None:
        if not self.is_active or self.sim is None:
            return
        v, w = conv.twist_command(msg)
        if not (math.isfinite(v) and math.isfinite(w)):
            self.get_logger().warning(
                f"cmd_vel is not finite (linear.x {v}, angular.z {w}): stopping the base",
                throttle_duration_sec=2.0,
            )
        self.sim.command(v, w)
        self._commanded = True
        if self.config.lockstep:
            self._advance()

    def _lockstep_watch(self) -> None:
        """Lock-step: the first state once its subscribers matched; without an answer for ``lockstep_wait``:
        re-publish (before the first command) or advance."""
        if not self._published and self._subscribers_matched():
            self._publish()
            return
        if time.monotonic() - self._last_publish < self.config.lockstep_wait:
            return
        if not self._commanded:
            self._publish()
            return
        self.silent_steps += 1
        if self.silent_steps == 1 or self.silent_steps % 50 == 0:
            self.get_logger().warning(
                f"no cmd_vel for {self.config.lockstep_wait} s: advancing on its own "
                f"(the base stops {self.config.cmd_timeout} s of sim time after the last command)"
            )
        self._advance()

    def _real_time_step(self) -> None:
        assert self.sim is not None
        self.sim.advance(self._tick())
        self.steps += 1
        self._publish()

    def _advance(self) -> None:
        assert self.sim is not None
        timeouts = self.sim.events.cmd_timeouts
        self.sim.advance(self.config.control_period)
        self.steps += 1
        if self.sim.events.cmd_timeouts > timeouts:
            self.get_logger().warning(
                f"no command for {self.config.cmd_timeout} s of sim time: the base stopped at t={self.sim.time:.2f} s"
            )
        self._publish()

    # ------------------------------------------------------------------------------------------- outputs --
    def _publish(self) -> None:
        """The state at sim time: clock first (stamps are never ahead of it), then odom, tf, scan, status."""
        sim, c = self.sim, self.config
        assert sim is not None and sim.latest_scan is not None
        self.clock_pub.publish(conv.clock_msg(sim.time))
        self.odom_pub.publish(conv.odometry_msg(sim, c.odom_frame, c.base_frame))
        if self.tf_pub is not None:
            self.tf_pub.publish(conv.tf_msg(sim, c.odom_frame, c.base_frame))
        self.truth_pub.publish(conv.truth_msg(sim, c.world_frame, c.base_frame))
        period = c.control_period if c.lockstep else self._tick()
        self.scan_pub.publish(conv.laser_msg(sim.latest_scan, c.laser_frame, period))
        self.status_pub.publish(conv.status_msg(sim, self.steps, self.silent_steps))
        self._last_publish = time.monotonic()
        self._published = True


def main(args: list[str] | None = None) -> int:
    return run_node("mujoco_sim_node", MujocoSimNode, args)


if __name__ == "__main__":
    sys.exit(main())
