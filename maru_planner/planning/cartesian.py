"""Cartesian paths (MoveIt's ``compute_cartesian_path``): a link along straight task-space lines.

From the start state, the link's pose is interpolated towards each waypoint in turn (position on the
line, orientation by the shortest rotation) in steps of at most ``max_step`` m (and ``max_step`` /
:data:`ROTATION_STEP_RADIUS` rad). Each step is solved by a few damped least-squares iterations from
the previous state, on the group's joints only, so the joints follow the line continuously. The path
stops at the first step that

- has no IK solution close to the previous state (unreachable, a joint limit or a singularity),
- jumps in joint space: a step longer than ``jump_threshold`` x the mean step (MoveIt's relative test),
- collides (``avoid_collisions``): a state is invalid, or the certifier (``docs/certification.md``)
  cannot prove the joint-space segment to it collision-free with the planner's safety margin.

The answer reports the ``fraction`` of the requested steps achieved and a trajectory through the
achieved states, timed by :mod:`maru_planner.trajectory` (corners blended by at most
:data:`BLEND_DEVIATION` rad, blends certified like the path). Nothing is achieved (fraction 0) is an
error with its own status; a partial path is a success with the reason it stopped.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from maru_planner import errors
from maru_planner.planning.links import check_link
from maru_planner.planning.requests import check_free, start_configuration
from maru_planner.planning.types import PlanStatus, answer_json, set_failure
from maru_planner.robot.ik import DampedLeastSquares
from maru_planner.trajectory import CurveFree, Limits, Trajectory, certified_curve, check_scaling, parameterize

ROTATION_STEP_RADIUS = 0.1  # m: a rotation step of max_step / this radius moves a point this far as much as max_step
IK_ITERATIONS = 20
POSITION_TOLERANCE = 1e-4  # m
ROTATION_TOLERANCE = 1e-3  # rad
BLEND_DEVIATION = 0.01  # rad: the timed trajectory stays this close to the computed states' polyline
DAMPING = 1e-6
MAX_STEPS = 100_000  # interpolated poses of one request: each is an IK solve and a state (refused before allocating)


@dataclass
class CartesianRequest:
    """A Cartesian path query (module doc). ``waypoints``: 4x4 poses of ``link`` in the root frame.

    ``link`` empty = the group's end effector. ``jump_threshold`` 0 disables the jump test.
    """

    group: str
    start: dict[str, float]
    waypoints: list[np.ndarray]
    link: str = ""
    max_step: float = 0.01
    jump_threshold: float = 0.0
    avoid_collisions: bool = True
    velocity_scaling: float = 1.0
    acceleration_scaling: float = 1.0
    time_parameterization: str = ""
    time_budget: float = 5.0


@dataclass
class CartesianResult:
    """Answer to a :class:`CartesianRequest`; ``compute_cartesian_path`` never raises, it sets ``status``."""

    status: PlanStatus
    message: str = ""
    error: BaseException | None = None
    fraction: float = 0.0
    stop_reason: str = ""
    link: str = ""
    joint_names: list[str] = field(default_factory=list)
    path: np.ndarray | None = None  # (n, group joints): the achieved states, start first
    trajectory: Trajectory | None = None
    certified: bool = False
    min_clearance: float = math.inf
    seconds: float = 0.0

    @property
    def success(self) -> bool:
        return self.status is PlanStatus.SUCCESS

    def to_json_dict(self) -> dict:
        return {
            **answer_json(self),
            "fraction": self.fraction,
            "stop_reason": self.stop_reason,
            "link": self.link,
            "certified": self.certified,
            "min_clearance": self.min_clearance if math.isfinite(self.min_clearance) else None,
            "seconds": self.seconds,
        }


def default_link(robot, group: str) -> str:
    """The end-effector link moved by most of the group's joints; InvalidLink when that is not one link."""
    joints = {robot.model.getJointId(name) for name in robot.groups.get(group, ())}
    counts = {link: len(joints & _supporting_joints(robot, link)) for link in robot.end_effectors.values()}
    most = max(counts.values(), default=0)
    links = [link for link, count in counts.items() if count == most and count > 0]
    if len(links) != 1:
        raise errors.InvalidLink(
            f"group {group!r}: no single end effector among {sorted(counts)} (found {links}); name the link"
        )
    return links[0]


def _supporting_joints(robot, link: str) -> set[int]:
    """The joints that move ``link`` (its parent joint and every joint above it)."""
    j, out = robot.model.frames[robot.model.getFrameId(link)].parentJoint, set()
    while j > 0:
        out.add(j)
        j = robot.model.parents[j]
    return out


def segment_lengths(start: np.ndarray, waypoints: list[np.ndarray]) -> list[float]:
    """How far (m) each line start -> waypoint 0 -> waypoint 1 ... moves the link, a rotation counted at
    :data:`ROTATION_STEP_RADIUS` (the distance :func:`interpolate_poses` divides into steps)."""
    lengths, current = [], start
    for target in waypoints:
        rotation = pin.log3(current[:3, :3].T @ target[:3, :3])
        moved = float(np.linalg.norm(target[:3, 3] - current[:3, 3]))
        lengths.append(max(moved, float(np.linalg.norm(rotation)) * ROTATION_STEP_RADIUS))
        current = target
    return lengths


def check_step_count(start: np.ndarray, waypoints: list[np.ndarray], max_step: float) -> int:
    """How many poses :func:`interpolate_poses` makes; InvalidRequest (before anything is allocated) past
    :data:`MAX_STEPS`."""
    ratios = [length / max_step for length in segment_lengths(start, waypoints)]  # inf for a tiny max_step
    count = math.inf
    if all(ratio <= MAX_STEPS for ratio in ratios):  # NaN fails too
        count = sum(max(1, math.ceil(ratio)) for ratio in ratios)
    if count > MAX_STEPS:
        implied = count if math.isfinite(count) else sum(ratios)
        raise errors.InvalidRequest(
            f"max_step {max_step:.3g} m implies {implied:.3g} interpolated poses along {len(waypoints)} "
            f"waypoint(s), more than {MAX_STEPS}; raise max_step"
        )
    return int(count)


def interpolate_poses(start: np.ndarray, waypoints: list[np.ndarray], max_step: float) -> list[np.ndarray]:
    """The link poses along the lines start -> waypoint 0 -> waypoint 1 ..., excluding the start."""
    poses, current = [], start
    for target in waypoints:
        rotation = pin.log3(current[:3, :3].T @ target[:3, :3])
        distance = max(np.linalg.norm(target[:3, 3] - current[:3, 3]), np.linalg.norm(rotation) * ROTATION_STEP_RADIUS)
        steps = max(1, math.ceil(distance / max_step))
        for s in np.arange(1, steps + 1) / steps:
            pose = np.eye(4)
            pose[:3, 3] = (1 - s) * current[:3, 3] + s * target[:3, 3]
            pose[:3, :3] = current[:3, :3] @ pin.exp3(s * rotation)
            poses.append(pose)
        current = target
    return poses


class _StepIK:
    """Damped least squares (the IK's :class:`DampedLeastSquares`) from the previous state to one link pose,
    the group's joints only."""

    def __init__(self, robot, link: str, indices: np.ndarray):
        self.robot, self.link, self.indices = robot, link, indices
        self.all_free = np.ones(len(indices))
        self.lower, self.upper = robot.lower_limits[indices], robot.upper_limits[indices]

    def solve(self, q: np.ndarray, target: np.ndarray) -> np.ndarray | None:
        problem = DampedLeastSquares(self.robot, {self.link: target}, self.indices)
        q = q.copy()
        for _ in range(IK_ITERATIONS):
            problem.residual(q, True)
            e = problem.err
            if np.linalg.norm(e[:3]) < POSITION_TOLERANCE and np.linalg.norm(e[3:]) < ROTATION_TOLERANCE:
                return q
            step = problem.step(DAMPING, self.all_free)
            q[self.indices] = np.clip(q[self.indices] + step, self.lower, self.upper)
        return None


def compute_cartesian_path(context, request: CartesianRequest) -> CartesianResult:
    """The Cartesian path of ``request`` on the robot, checker and certifier of ``context`` (a
    :class:`~maru_planner.planning.context.PlanningContext`)."""
    t0 = time.monotonic()
    result = CartesianResult(status=PlanStatus.PLANNING_FAILED)
    try:
        _compute(context, request, result, t0)
    except errors.MaruError as exc:
        set_failure(result, exc)
        result.path = result.trajectory = None
    result.seconds = time.monotonic() - t0
    return result


def _compute(context, request: CartesianRequest, result: CartesianResult, t0: float) -> None:
    robot = context.robot
    deadline = t0 + _positive(request.time_budget, "time_budget")
    max_step = _positive(request.max_step, "max_step")
    jump = float(request.jump_threshold)
    if not (math.isfinite(jump) and jump >= 0.0):
        raise errors.InvalidRequest(f"jump_threshold must be a finite number >= 0, got {jump}")
    scalings = _scalings(request)
    indices = np.array(sorted(robot.group_joint_indices(request.group)), dtype=int)
    link = request.link or default_link(robot, request.group)
    check_link(robot, link)
    result.link, result.joint_names = link, [robot.joint_names[i] for i in indices]
    start = start_configuration(context.robot, request.start, indices)
    waypoints = [_pose(w, k) for k, w in enumerate(request.waypoints)]
    if not waypoints:
        raise errors.InvalidRequest("no waypoints: give at least one pose of the link")
    start_pose = robot.frame_pose(start, link)
    check_step_count(start_pose, waypoints, max_step)
    if request.avoid_collisions:
        check_free(context.checker, start, errors.StartInCollision, "start")
    poses = interpolate_poses(start_pose, waypoints, max_step)
    states, reason = _follow(robot, link, indices, start, poses, deadline)
    states, reason = _jump_cut(states, reason, jump)
    margin = end_margin(context, context.config.safety_margin, start) if request.avoid_collisions else 0.0
    if request.avoid_collisions:
        states, reason = _collision_cut(context, states, reason, deadline, margin, result)
    if len(states) < 2:
        error = errors.NoIKSolution if reason.startswith("no IK") else errors.PlanningFailed
        raise error(f"Cartesian path of {link}: nothing achieved, {reason}", source="cartesian")
    result.fraction = (len(states) - 1) / len(poses)
    result.stop_reason = reason
    result.path = states[:, indices]
    result.trajectory = _timed(context, request, states, indices, deadline, margin, scalings)
    result.status = PlanStatus.SUCCESS
    result.message = f"Cartesian path of {link}: {result.fraction:.1%} of {len(poses)} steps" + (
        f", stopped: {reason}" if reason else ""
    )


def _positive(value, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise errors.InvalidRequest(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(value) and value > 0.0):
        raise errors.InvalidRequest(f"{name} must be a finite number > 0, got {value}")
    return value


def _pose(value, k: int) -> np.ndarray:
    pose = np.asarray(value, dtype=float)
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise errors.InvalidRequest(f"waypoint {k} must be a finite 4x4 pose, got shape {pose.shape}")
    return pose


def _follow(robot, link, indices, start, poses, deadline) -> tuple[np.ndarray, str]:
    """States reaching each pose in turn, start first; stops at the first pose with no close IK solution."""
    ik = _StepIK(robot, link, indices)
    states = [start]
    for k, pose in enumerate(poses):
        if time.monotonic() > deadline:
            return np.array(states), f"time budget ran out at step {k + 1} of {len(poses)}"
        q = ik.solve(states[-1], pose)
        if q is None:
            return np.array(states), f"no IK solution near the previous state at step {k + 1} of {len(poses)}"
        states.append(q)
    return np.array(states), ""


def _jump_cut(states: np.ndarray, reason: str, threshold: float) -> tuple[np.ndarray, str]:
    """MoveIt's relative jump test: cut before the first step longer than ``threshold`` x the mean step."""
    if threshold <= 0.0 or len(states) < 3:
        return states, reason
    steps = np.linalg.norm(np.diff(states, axis=0), axis=1)
    jumps = np.flatnonzero(steps > threshold * steps.mean())
    if not len(jumps):
        return states, reason
    k = int(jumps[0])
    return states[: k + 1], f"joint-space jump of {steps[k]:.3f} rad at step {k + 1} (mean step {steps.mean():.4f})"


def end_margin(context, margin: float, *ends: np.ndarray) -> float:
    """``margin`` (m), lowered to half the ``ends``' smallest clearance when that is closer; 0 without a
    certifier."""
    if context.certifier is None:
        return 0.0
    clearance = min(context.certifier.clearance(q) for q in ends)
    return min(margin, 0.5 * max(clearance, 0.0))


def _collision_cut(context, states, reason: str, deadline: float, margin: float, result) -> tuple[np.ndarray, str]:
    """Cut before the first invalid state, then before the first segment the certifier cannot prove."""
    bad = context.checker.first_invalid(states)
    if bad >= 0:
        pairs = context.checker.colliding_pairs(states[bad])
        named = ", ".join(f"{a}–{b}" for a, b in pairs[:3])
        states, reason = states[:bad], f"collision at step {bad}: {named}"
    certifier = context.certifier
    if certifier is None or len(states) < 2:
        return states, reason
    certificate = certifier.certify_path(states, deadline, margin=margin)
    result.min_clearance = certificate.min_clearance
    if certificate.valid:
        result.certified = True
        return states, reason
    k = certificate.first_failing_segment
    result.certified = k > 0
    return states[: k + 1], f"segment {k + 1} not certified collision-free ({certificate.reason})"


def _scalings(request: CartesianRequest) -> tuple[float, float]:
    """The request's velocity and acceleration scalings, checked before any work."""
    return (check_scaling(request.velocity_scaling, "velocity_scaling"),
            check_scaling(request.acceleration_scaling, "acceleration_scaling"))  # fmt: skip


def _timed(context, request: CartesianRequest, states, indices, deadline: float, margin: float,
           scalings: tuple[float, float]) -> Trajectory:  # fmt: skip
    method = request.time_parameterization or context.config.time_parameterization
    certifier = context.certifier if request.avoid_collisions else None
    return time_dense_path(context.robot, context.config, certifier, states, indices, method, scalings, deadline,
                           margin)  # fmt: skip


def time_dense_path(robot, config, certifier, states: np.ndarray, indices: np.ndarray, method: str,
                    scalings: tuple[float, float], deadline: float, margin: float) -> Trajectory:  # fmt: skip
    """A trajectory through the full configurations ``states`` (only ``indices`` move) that stays within
    :data:`BLEND_DEVIATION` rad of their polyline; blends certified by ``certifier`` (None: unchecked)."""
    limits = Limits.scaled(robot.velocity_limits[indices], robot.acceleration_limits[indices], *scalings)
    curve_free: CurveFree = _unchecked
    if certifier is not None:
        curve_free = certified_curve(certifier, states[0], indices, deadline, margin)
    trajectory, _report = parameterize(
        states[:, indices],
        [robot.joint_names[i] for i in indices],
        limits,
        method,
        curve_free=curve_free,
        max_deviation=BLEND_DEVIATION,
        dt=config.trajectory_dt,
        max_points=config.max_trajectory_points,
        deadline=deadline,
        certify_step=config.resolution,
        sample_deadline=deadline,
    )
    return trajectory


def _unchecked(_states: np.ndarray, _chord_deviation: np.ndarray) -> bool:
    """The blend check of a path planned without collision avoidance: none."""
    return True
