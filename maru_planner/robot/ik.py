"""Inverse kinematics for any robot: the robot's own strategies first, then damped least squares.

- ``solve_ik``: tries the robot profile's IK strategies (``robot.ik_strategies``, e.g. Maru-1's
  closed-form arms and two-hand scheme in :mod:`maru_planner.robot.robots.maru1`), then ``solve_ik_numeric``.
- ``solve_ik_numeric``: Levenberg-Marquardt-damped least squares on Pinocchio frame Jacobians, any
  number of frame targets, restricted to a group's joints, clamped to joint limits, with random restarts.

An IK strategy is ``strategy(robot, targets, q_seed, group, deadline=..., is_valid=...)``: a full
configuration, ``None`` when the request is not one it handles, or NoIKSolution when it tried and failed.
Time limits: ``deadline`` is an absolute ``time.monotonic()`` value.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from maru_planner.errors import InvalidRequest, NoIKSolution
from maru_planner.robot.ik_strategy import IKStrategy, Validity  # noqa: F401 (IKStrategy: re-exported, its old home)
from maru_planner.robot.model import RobotModel

LOCAL = pin.ReferenceFrame.LOCAL


def _se3(T: np.ndarray) -> pin.SE3:
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise InvalidRequest(f"IK target must be a finite 4x4 pose, got shape {T.shape}")
    return pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())


class DampedLeastSquares:
    """One robot + targets: residual, Jacobian and damped steps, buffers reused across iterations."""

    def __init__(self, robot: RobotModel, targets: Mapping[str, np.ndarray], idx: np.ndarray):
        self.robot, self.idx = robot, idx
        self.fids = [robot.frame_id(f) for f in targets]
        self.goals = [_se3(T) for T in targets.values()]
        self.data = robot.model.createData()
        m = 6 * len(self.fids)
        self.err = np.zeros(m)
        self.trial_err = np.zeros(m)
        self.J = np.zeros((m, len(idx)))

    def residual(self, q: np.ndarray, with_jacobian: bool) -> float:
        """Norm of the stacked errors at q; with_jacobian also refreshes ``err`` and ``J`` (else ``trial_err``)."""
        model, data = self.robot.model, self.data
        err = self.err if with_jacobian else self.trial_err
        if with_jacobian:
            pin.computeJointJacobians(model, data, q)
        else:
            pin.forwardKinematics(model, data, q)
        for k, (fid, goal) in enumerate(zip(self.fids, self.goals)):
            iMd = pin.updateFramePlacement(model, data, fid).actInv(goal)
            err[6 * k : 6 * k + 6] = pin.log6(iMd).vector  # in the frame, exact Jacobian below
            if with_jacobian:
                J = pin.getFrameJacobian(model, data, fid, LOCAL)
                self.J[6 * k : 6 * k + 6] = pin.Jlog6(iMd.inverse()) @ J[:, self.idx]
        return float(np.linalg.norm(err))

    def step(self, damping: float, free: np.ndarray) -> np.ndarray:
        """Damped least-squares step using only the ``free`` joints (the others get 0)."""
        J, e = self.J * free, self.err
        damped = J @ J.T + damping * np.eye(len(e))
        try:
            return J.T @ np.linalg.solve(damped, e)
        except np.linalg.LinAlgError:  # singular to machine precision (a target far beyond reach): no step
            return np.zeros(J.shape[1])


def solve_ik(
    robot: RobotModel,
    targets: Mapping[str, np.ndarray],
    q_seed: np.ndarray,
    group: str | None = None,
    *,
    deadline: float | None = None,
    is_valid: Validity | None = None,
    **numeric: Any,
) -> np.ndarray:
    """A full configuration putting each target frame at its 4x4 pose (root frame).

    The robot's IK strategies are tried first, in order; then :func:`solve_ik_numeric` (which takes
    the ``numeric`` keywords: ``tol``, ``max_restarts``, ``rng``, ``max_iters``, ``max_step``).
    Raises NoIKSolution with every attempt's reason.
    """
    q_seed = _checked_seed(robot, targets, q_seed)
    reasons = []
    for strategy in robot.ik_strategies:
        try:
            q = strategy(robot, targets, q_seed, group, deadline=deadline, is_valid=is_valid)
        except NoIKSolution as exc:
            reasons.append(str(exc))
            continue
        if q is not None:
            return q
    try:
        return solve_ik_numeric(robot, targets, q_seed, group, deadline=deadline, is_valid=is_valid, **numeric)
    except NoIKSolution as exc:
        raise NoIKSolution("; ".join([*reasons, str(exc)])) from None


def _checked_seed(robot: RobotModel, targets: Mapping[str, np.ndarray], q_seed: np.ndarray) -> np.ndarray:
    if not targets:
        raise InvalidRequest("IK needs at least one target frame")
    q_seed = np.asarray(q_seed, dtype=float)
    if q_seed.shape != (robot.nq,) or not np.all(np.isfinite(q_seed)):
        raise InvalidRequest(f"IK seed must be {robot.nq} finite values, got shape {q_seed.shape}")
    return q_seed


def solve_ik_numeric(
    robot: RobotModel,
    targets: Mapping[str, np.ndarray],
    q_seed: np.ndarray,
    group: str | None = None,
    *,
    tol: float = 1e-6,
    max_restarts: int = 20,
    rng: np.random.Generator | None = None,
    deadline: float | None = None,
    max_iters: int = 150,
    max_step: float = 0.5,
    is_valid: Validity | None = None,
) -> np.ndarray:
    """Damped least squares: a full configuration putting each target frame at its 4x4 pose.

    Only the group's joints move (all joints for ``group=None``); the others
    keep their ``q_seed`` values. The first attempt starts at the seed, the
    next ``max_restarts`` at uniform random configurations. A solution must
    be within limits, reach every target to ``tol`` (norm of the stacked
    log6 errors, m and rad) and pass ``is_valid`` if given.
    Raises NoIKSolution naming the frames and the best residual reached.
    """
    q_seed = _checked_seed(robot, targets, q_seed)
    idx = robot.group_joint_indices(group)
    problem = DampedLeastSquares(robot, targets, idx)
    rng = rng or np.random.default_rng()
    lo, hi = robot.lower_limits[idx], robot.upper_limits[idx]
    revolute = _revolute_mask(robot)[idx]
    best = math.inf
    rejected = 0
    for attempt in range(max_restarts + 1):
        if deadline is not None and time.monotonic() > deadline:
            break
        q = np.clip(q_seed, robot.lower_limits, robot.upper_limits)
        if attempt > 0:
            q[idx] = rng.uniform(lo, hi)
        residual = _attempt(problem, q, lo, hi, revolute, tol, max_iters, max_step, deadline)
        best = min(best, residual)
        if residual <= tol:
            if is_valid is None or is_valid(q):
                return q
            rejected += 1
    frames = ", ".join(targets)
    extra = f"; {rejected} solution(s) rejected as invalid (collision)" if rejected else ""
    raise NoIKSolution(f"no IK solution for [{frames}]: best residual {best:.3g} > tol {tol:g}{extra}")


def _revolute_mask(robot: RobotModel) -> np.ndarray:
    """True for revolute joints (RX/RY/RZ/unaligned): their angles may be shifted by 2*pi."""
    names = [robot.model.joints[j].shortname() for j in range(1, robot.model.njoints)]
    return np.array([n.startswith("JointModelR") and "Unbounded" not in n for n in names])


def _attempt(problem: DampedLeastSquares, q, lo, hi, revolute, tol, max_iters, max_step, deadline) -> float:
    """Descend with revolute limits relaxed, wrap angles into the limits; if that fails, descend with limits."""
    idx = problem.idx
    loose_lo = np.where(revolute, lo - 2 * np.pi, lo)
    loose_hi = np.where(revolute, hi + 2 * np.pi, hi)
    start = q.copy()
    residual = _descend(problem, q, loose_lo, loose_hi, tol, max_iters, max_step, deadline)
    if residual <= tol:
        for i, k in enumerate(idx):
            if revolute[i]:
                wrapped = wrap_into(q[k], lo[i], hi[i], q[k])
                q[k] = q[k] if wrapped is None else wrapped
        if np.all(q[idx] >= lo - 1e-12) and np.all(q[idx] <= hi + 1e-12):
            return problem.residual(q, False)
        q[:] = start
    q[idx] = np.clip(q[idx], lo, hi)
    return _descend(problem, q, lo, hi, tol, max_iters, max_step, deadline)


def _descend(problem: DampedLeastSquares, q, lo, hi, tol, max_iters, max_step, deadline) -> float:
    """Damped Gauss-Newton from q (modified in place); returns the final residual."""
    idx = problem.idx
    residual = problem.residual(q, True)
    damping = 1e-3
    for it in range(max_iters):
        if residual <= tol:
            break
        if deadline is not None and it % 16 == 15 and time.monotonic() > deadline:
            break
        # joints resting on a limit and pushed outward are frozen for this step (active set)
        free = np.ones(len(idx))
        for _ in range(3):
            dq = problem.step(damping, free)
            blocked = ((q[idx] <= lo + 1e-12) & (dq < 0)) | ((q[idx] >= hi - 1e-12) & (dq > 0))
            if not np.any(blocked & (free > 0)):
                break
            free[blocked] = 0.0
        scale = np.max(np.abs(dq))
        if scale > max_step:
            dq *= max_step / scale
        trial = q.copy()
        trial[idx] = np.clip(q[idx] + dq, lo, hi)
        new_residual = problem.residual(trial, False)
        if new_residual < residual:
            q[:] = trial
            residual = problem.residual(q, True)
            damping = max(damping * 0.3, 1e-9)
        else:
            damping *= 10.0
            if damping > 1e4:
                break
    return residual


def wrap_into(value: float, lo: float, hi: float, near: float) -> float | None:
    """value + 2*pi*k inside [lo, hi], the one closest to ``near``; None if none."""
    options = [value + 2 * math.pi * k for k in (-2, -1, 0, 1, 2)]
    inside = [v for v in options if lo - 1e-9 <= v <= hi + 1e-9]
    return min(inside, key=lambda v: abs(v - near)) if inside else None
