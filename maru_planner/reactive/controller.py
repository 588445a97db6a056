"""ElasticStripController: one laser scan in, one (v, w) + strip + arm step out (paper 001, Fig. 17)."""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from maru_planner.errors import InvalidRequest
from maru_planner.params import ParamSpec, dataclass_params, param
from maru_planner.reactive.arm import ArmReactive
from maru_planner.reactive.forces import external_forces
from maru_planner.reactive.kinematics import clamp_twist, wrap_angle
from maru_planner.reactive.scan import LaserScanData, obstacle_check, scan_to_points, to_world
from maru_planner.reactive.strip import ElasticStrip
from maru_planner.reactive.vias import ViaTarget


@dataclass
class StripParams:
    """Parameters of the reactive layer. Defaults: the paper's gains and the Silvermate base.

    Each field is a declared parameter (:func:`maru_planner.params.param`): reactive_node makes
    it a ROS parameter with this description and range, and every value is checked on creation.
    """

    k_r: float = param(0.5, "repulsion gain (paper)", lower=1e-3, upper=100.0)
    k_c: float = param(0.3, "contraction gain (paper)", lower=1e-3, upper=10.0)
    d_safe: float = param(
        0.45, "m, safety margin added to the robot radius: d_0 = d_safe + robot_radius", lower=0.0, upper=5.0
    )
    robot_radius: float = param(0.30, "m, d_r: the base's radius", lower=0.01, upper=5.0)
    num_vias: int = param(20, "via points in the strip", lower=3, upper=1000)
    via_spacing: float = param(0.30, "m between vias on the reference path", lower=0.05, upper=5.0)
    strip: str = param(
        "modified", "modified (eq. 41-42) or plain (eq. 39) external force", choices=("modified", "plain")
    )
    head_on_ratio: float = param(
        0.25, "modified strip: head-on rule threshold, 0 = off (see forces.py)", lower=0.0, upper=10.0
    )
    suppress_tangential: bool = param(True, "drop the along-strip part of external forces on vias (elastic bands)")
    iterations: int = param(2, "force steps per update", lower=1, upper=100)
    max_via_step: float = param(0.2, "m a via moves at most per iteration", lower=1e-3, upper=5.0)
    max_linear: float = param(0.5, "m/s, linear speed limit", lower=1e-3, upper=10.0)
    max_angular: float = param(1.0, "rad/s, turn rate limit", lower=1e-3, upper=10.0)
    k_angular: float = param(2.0, "turn rate per rad of heading error", lower=1e-3, upper=100.0)
    lookahead: float = param(0.6, "m along the strip to the base target", lower=0.01, upper=20.0)
    target_margin: float = param(
        0.05, "m: the drive to the target must clear scan points by robot_radius + this", lower=0.0, upper=2.0
    )
    beam_window: tuple[int, int] | None = param(
        (31, 331), "beams [lo, hi) of obstacle_check (the paper's central 150 deg of a 361-beam LMS200)"
    )
    avoidance_range: float = param(1.5, "m, obstacle_check threshold (AVOIDANCE_RANGE)", lower=0.01, upper=100.0)
    force_range: float = param(8.0, "m: scan points farther than this exert no force", lower=0.01, upper=1000.0)
    is_sort_radius: float = param(0.5, "m per axis, IsSort filter of inserted vias", lower=0.0, upper=10.0)
    is_sort_rule: str = param(
        "either_axis", "IsSort rule: the paper's code (either_axis) or both_axes", choices=("either_axis", "both_axes")
    )
    use_via_events: bool = param(True, "insert the paper's avoidance via (SortPosition / IsSort)")
    via_reach: float = param(0.35, "m: an inserted via counts as reached", lower=0.0, upper=10.0)
    goal_tolerance: float = param(0.25, "m: the goal counts as reached", lower=0.01, upper=10.0)
    slow_radius: float = param(
        0.8, "m: linear speed ramps down inside this distance of the goal (0 = off)", lower=0.0, upper=100.0
    )
    stop_distance: float = param(0.0, "m: stop if a scan point is this close in front (0 = off)", lower=0.0, upper=10.0)
    laser_pose: tuple[float, float, float] = param((0.22, 0.0, 0.0), "laser in base_link: x (m), y (m), yaw (rad)")
    arm_enabled: bool = param(True, "run the arm update (eq. 46-49)")
    arm_d_safe: float = param(0.10, "m, the arms' safety margin", lower=0.0, upper=2.0)
    arm_link_radius: float = param(0.055, "m, arm link radius", lower=0.0, upper=1.0)
    arm_alpha: float = param(1.0, "joint step per unit torque", lower=0.0, upper=100.0)
    arm_max_joint_step: float = param(0.05, "rad per update and joint", lower=1e-4, upper=1.0)

    def __post_init__(self):
        for name, spec in _strip_specs().items():
            if name not in ("beam_window", "laser_pose"):
                setattr(self, name, spec.check(getattr(self, name)))
        if self.beam_window is not None:
            window = tuple(self.beam_window)
            if len(window) != 2 or not all(float(v).is_integer() for v in window) or not 0 <= window[0] < window[1]:
                raise InvalidRequest(f"beam_window must be [lo, hi] with 0 <= lo < hi, got {list(window)}")
            self.beam_window = (int(window[0]), int(window[1]))
        pose = tuple(float(v) for v in self.laser_pose)
        if len(pose) != 3 or not all(math.isfinite(v) and abs(v) <= 10.0 for v in pose):
            raise InvalidRequest(f"laser_pose must be [x, y, yaw] with finite values within 10, got {list(pose)}")
        self.laser_pose = pose

    @property
    def d0(self) -> float:
        return self.d_safe + self.robot_radius

    @classmethod
    def from_dict(cls, values: dict) -> StripParams:
        """StripParams from a mapping such as a parsed params file (lists for the tuple fields)."""
        unknown = sorted(set(values) - set(_strip_specs()))
        if unknown:
            raise InvalidRequest(f"unknown StripParams field(s): {', '.join(unknown)}")
        return cls(**values)


@functools.cache
def _strip_specs() -> dict[str, ParamSpec]:
    return dataclass_params(StripParams)


@dataclass
class ControlOutput:
    """Result of one update. Points and strip are in the world (odometry) frame."""

    v: float
    w: float
    strip: np.ndarray
    target: tuple[float, float]
    reached_goal: bool
    obstacle_points: np.ndarray
    arm_joint_steps: np.ndarray | None = None
    arm_joint_positions: np.ndarray | None = None
    update_time: float = 0.0
    obstacle_event: bool = False
    via_active: bool = False
    robot_force: tuple[float, float] = (0.0, 0.0)
    work: dict = field(default_factory=dict)


class ElasticStripController:
    """Modified (or plain) elastic strip on a diff-drive base with two reactive arms."""

    def __init__(self, params: StripParams | None = None):
        self.params = params or StripParams()
        p = self.params
        self.strip = _make_strip(p)
        self.via = ViaTarget(reach=p.via_reach, blocked_radius=p.robot_radius)
        self.arm = ArmReactive(**_arm_settings(p)) if p.arm_enabled else None
        self.goal: np.ndarray | None = None
        self._needs_start = True
        self._pairs_seen = 0
        self._blocked = False

    def set_params(self, params: StripParams) -> None:
        """Apply new parameters from the next update on, keeping the goal, the strip's shape and the arm state.

        The strip is rebuilt with the new gains and spacing on what is left of its path (the
        deformed vias, then the rest of the reference path); the arm keeps its joint positions
        (a newly enabled arm starts at its nominal posture).
        """
        remaining = None if self._needs_start or self.goal is None else self.strip.remaining_path()
        self.params = params
        self.strip = _make_strip(params)
        if remaining is not None:
            self.strip.set_path(remaining)
        self._pairs_seen = 0
        self.via.reach, self.via.blocked_radius = params.via_reach, params.robot_radius
        if not params.arm_enabled:
            self.arm = None
        elif self.arm is None:
            self.arm = ArmReactive(**_arm_settings(params))
        else:
            self.arm.configure(**_arm_settings(params))

    # -- inputs -------------------------------------------------------------------------------
    def set_goal(self, goal) -> None:
        """Goal (x, y[, theta]). Without a path the initial path is the straight line to it."""
        goal = np.asarray(goal, dtype=float).reshape(-1)
        if goal.size not in (2, 3) or not np.all(np.isfinite(goal)):
            raise InvalidRequest(f"goal must be 2 or 3 finite numbers, got {goal}")
        self.goal = np.array([goal[0], goal[1], goal[2] if goal.size == 3 else 0.0])
        self._needs_start = True
        self.via.clear()

    def set_path(self, path) -> None:
        """Initial path (n, 2|3) in the world frame; its last point becomes the goal unless one is set after."""
        path = np.asarray(path, dtype=float)
        self.strip.set_path(path)  # checks the shape and values
        last = path[-1]
        self.goal = np.array([last[0], last[1], last[2] if path.shape[1] == 3 else 0.0])
        self._needs_start = False
        self.via.clear()

    @property
    def has_goal(self) -> bool:
        return self.goal is not None

    # -- update ---------------------------------------------------------------------------------
    def update(self, pose, scan: LaserScanData) -> ControlOutput:
        """One scan in, one command out: O(beams * vias), independent of run time."""
        t0 = time.perf_counter()
        p = self.params
        if self.goal is None:
            raise RuntimeError("ElasticStripController has no goal; call set_goal or set_path first")
        pose = np.asarray(pose, dtype=float).reshape(-1)
        if pose.size != 3 or not np.all(np.isfinite(pose)):
            raise InvalidRequest(f"pose must be 3 finite numbers (x, y, theta), got {pose}")
        scan.validate()
        if self._needs_start:
            self.strip.set_path(np.vstack([pose[:2], self.goal[:2]]))
            self._needs_start = False
        position = pose[:2]

        points_robot = scan_to_points(scan, p.laser_pose, None, max_range=p.force_range)
        points_world = to_world(points_robot, pose)

        self.strip.anchor(position)
        self.strip.deform(points_world)
        strip = self.strip.vias

        dist_goal = float(np.hypot(*(self.goal[:2] - position)))
        event = obstacle_check(scan, p.avoidance_range, p.beam_window) is not None
        target = self._choose_target(position, strip, points_world, event, dist_goal, self.goal)

        robot_force = self._robot_force(position, target, points_world)
        v, w, reached = self._command(pose, target, robot_force, dist_goal, points_robot)

        arm_steps = arm_q = None
        if self.arm is not None:
            arm_steps, _ = self.arm.step(points_robot)
            arm_q = self.arm.q.copy()
        pairs_before = self._pairs_seen
        self._pairs_seen = self.strip.pair_evaluations
        work = {
            "beams": int(scan.ranges.size),
            "points": int(len(points_world)),
            "vias": int(len(strip)),
            "force_evaluations": self.strip.iterations,
            "pair_evaluations": self.strip.pair_evaluations - pairs_before,
        }
        return ControlOutput(
            v=v,
            w=w,
            strip=strip,
            target=(float(target[0]), float(target[1])),
            reached_goal=reached,
            obstacle_points=points_world,
            arm_joint_steps=arm_steps,
            arm_joint_positions=arm_q,
            update_time=time.perf_counter() - t0,
            obstacle_event=event,
            via_active=self.via.active,
            robot_force=(float(robot_force[0]), float(robot_force[1])),
            work=work,
        )

    def _choose_target(
        self, position, strip, points_world, event: bool, dist_goal: float, goal: np.ndarray
    ) -> np.ndarray:
        """The inserted avoidance via if one is active (sec. 4-5), else the clear lookahead via of the strip."""
        p = self.params
        look_idx, look_point = self.strip.lookahead(p.lookahead)
        self._blocked = False
        look_idx, look_point = self._clear_target(position, strip, look_idx, points_world)
        if p.use_via_events:
            goal_dir = (goal[:2] - position) / max(dist_goal, 1e-9)
            self.via.refresh(position, goal_dir, points_world)
            if event and look_idx > 0:
                current = self.via.point if self.via.point is not None else goal[:2]
                self.via.offer(look_point, current, p.is_sort_radius, p.is_sort_rule)
        if self.via.point is not None and not self._segment_clear(position, self.via.point, points_world):
            self.via.clear()
        return self.via.point if self.via.point is not None else look_point

    def _segment_clear(self, start: np.ndarray, end: np.ndarray, points: np.ndarray) -> bool:
        """Does the straight drive start -> end keep the body (robot_radius) off every scan point?"""
        if len(points) == 0:
            return True
        seg = end - start
        length2 = float(seg @ seg)
        rel = points - start
        s = np.clip(rel @ seg / length2, 0.0, 1.0) if length2 > 1e-12 else np.zeros(len(points))
        closest = start + s[:, None] * seg
        clearance = self.params.robot_radius + self.params.target_margin
        return bool(np.min(np.hypot(*(points - closest).T)) > clearance)

    def _clear_target(self, position, strip, look_idx, points):
        """The farthest via up to the lookahead one whose straight segment from the robot is clear (else via 1)."""
        if len(points) == 0 or look_idx <= 1:
            return look_idx, strip[look_idx].copy()
        near = points[np.hypot(*(points - position).T) < self.params.lookahead + 2 * self.params.robot_radius]
        for idx in range(look_idx, 0, -1):
            if self._segment_clear(position, strip[idx], near):
                return idx, strip[idx].copy()
        self._blocked = True
        return 1, strip[1].copy()

    def _robot_force(self, position: np.ndarray, target: np.ndarray, points: np.ndarray) -> np.ndarray:
        """External force on the base's own control point (eq. 39/41 at the robot)."""
        if len(points) == 0:
            return np.zeros(2)
        direction = target - position
        norm = np.hypot(*direction)
        tangent = direction / norm if norm > 1e-9 else np.array([1.0, 0.0])
        p = self.params
        return external_forces(
            position[None, :],
            tangent[None, :],
            points,
            p.d0,
            p.k_r,
            p.strip,
            p.head_on_ratio,
            min_gap=2.0 * p.robot_radius,
        )[0]

    def _command(self, pose, target, robot_force, dist_goal, points_robot):
        """Eq. 43-45: Δ = (target - current) + F, heading atan2(Δ); then a unicycle law within limits."""
        p = self.params
        if dist_goal < p.goal_tolerance:
            return 0.0, 0.0, True
        delta = (np.asarray(target) - pose[:2]) + robot_force
        heading = math.atan2(delta[1], delta[0])
        err = wrap_angle(heading - pose[2])
        w = p.k_angular * err
        v = p.max_linear * max(math.cos(err), 0.0) ** 2
        v *= min(1.0, dist_goal / p.slow_radius) if p.slow_radius > 0 else 1.0
        if abs(err) > math.pi / 2 or (self._blocked and not self.via.active):
            v = 0.0  # turn in place: behind us, or no straight drive along the strip is clear
        if p.stop_distance > 0 and len(points_robot):
            ahead = (points_robot[:, 0] > 0) & (np.abs(points_robot[:, 1]) < p.robot_radius)
            if np.any(np.hypot(*points_robot[ahead].T) < p.robot_radius + p.stop_distance):
                v = 0.0
        v, w = clamp_twist(v, w, p.max_linear, p.max_angular)
        return float(v), float(w), False


def _make_strip(p: StripParams) -> ElasticStrip:
    return ElasticStrip(
        p.num_vias,
        p.via_spacing,
        p.k_c,
        p.k_r,
        p.d0,
        p.strip,
        p.iterations,
        p.max_via_step,
        p.head_on_ratio,
        p.suppress_tangential,
        min_gap=2.0 * p.robot_radius,
    )


def _arm_settings(p: StripParams) -> dict[str, Any]:
    """The keywords of ``ArmReactive`` / ``ArmReactive.configure`` (gains, margin, step, strip kind)."""
    return {
        "k_c": p.k_c,
        "k_r": p.k_r,
        "d0": p.arm_d_safe + p.arm_link_radius,
        "alpha": p.arm_alpha,
        "max_joint_step": p.arm_max_joint_step,
        "strip": p.strip,
    }
