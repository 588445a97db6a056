"""Inverse kinematics: damped least squares for any robot, and paper 000's two-hand scheme for Maru-1.

- ``solve_ik``: Levenberg-Marquardt-damped least squares on Pinocchio frame
  Jacobians, any number of frame targets, restricted to a group's joints,
  clamped to joint limits, with random restarts (paper-independent).
- ``arm_ik_closed_form``: exact geometric 6-DOF arm IK for Maru-1, following
  sec. III.2.2 (wrist point, elbow on two spheres and a plane, then
  theta1..theta6) with the printed formulas' errors fixed (docs/robot.md).
- ``two_hand_ik``: the paper's scheme: waist angle from the two hand targets
  (eq. 5-6), then each arm on its own (eq. 7-8).

Time limits: ``deadline`` is an absolute ``time.monotonic()`` value.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping

import numpy as np
import pinocchio as pin

from maru_planner.errors import InvalidRequest, NoIKSolution
from maru_planner.robot.model import RobotModel

Validity = Callable[[np.ndarray], bool]
LOCAL = pin.ReferenceFrame.LOCAL


def _se3(T: np.ndarray) -> pin.SE3:
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise InvalidRequest(f"IK target must be a finite 4x4 pose, got shape {T.shape}")
    return pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())


class _DLS:
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
        return J.T @ np.linalg.solve(J @ J.T + damping * np.eye(len(e)), e)


def solve_ik(
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
    """A full configuration putting each target frame at its 4x4 pose (root frame).

    Only the group's joints move (all joints for ``group=None``); the others
    keep their ``q_seed`` values. The first attempt starts at the seed, the
    next ``max_restarts`` at uniform random configurations. A solution must
    be within limits, reach every target to ``tol`` (norm of the stacked
    log6 errors, m and rad) and pass ``is_valid`` if given.
    Raises NoIKSolution naming the frames and the best residual reached.
    """
    if not targets:
        raise InvalidRequest("IK needs at least one target frame")
    q_seed = np.asarray(q_seed, dtype=float)
    if q_seed.shape != (robot.nq,) or not np.all(np.isfinite(q_seed)):
        raise InvalidRequest(f"IK seed must be {robot.nq} finite values, got shape {q_seed.shape}")
    idx = robot.group_joint_indices(group)
    analytic = _maru_arm_closed_form(robot, targets, q_seed, group, is_valid)
    if analytic is not None:
        return analytic
    problem = _DLS(robot, targets, idx)
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


def _attempt(problem: _DLS, q, lo, hi, revolute, tol, max_iters, max_step, deadline) -> float:
    """Descend with revolute limits relaxed, wrap angles into the limits; if that fails, descend with limits."""
    idx = problem.idx
    loose_lo = np.where(revolute, lo - 2 * np.pi, lo)
    loose_hi = np.where(revolute, hi + 2 * np.pi, hi)
    start = q.copy()
    residual = _descend(problem, q, loose_lo, loose_hi, tol, max_iters, max_step, deadline)
    if residual <= tol:
        for i, k in enumerate(idx):
            if revolute[i]:
                wrapped = _wrap_into(q[k], lo[i], hi[i], q[k])
                q[k] = q[k] if wrapped is None else wrapped
        if np.all(q[idx] >= lo - 1e-12) and np.all(q[idx] <= hi + 1e-12):
            return problem.residual(q, False)
        q[:] = start
    q[idx] = np.clip(q[idx], lo, hi)
    return _descend(problem, q, lo, hi, tol, max_iters, max_step, deadline)


def _descend(problem: _DLS, q, lo, hi, tol, max_iters, max_step, deadline) -> float:
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


# ------------------------------------------------------------------- Maru-1 --
def waist_angle_from_hands(right_position: np.ndarray, left_position: np.ndarray) -> float:
    """Eq. 5-6: the body faces the midpoint of the two hand targets (x, y only).

    The printed eq. 5 subtracts (o_r - o_l)/2, but the text asks for the
    midpoint and the difference would turn a symmetric reach by -90 deg: the
    sum is used. ``asin(c.y/|c|)`` equals ``atan2(c.y, c.x)`` for c.x >= 0;
    atan2 also covers targets behind the body.
    """
    c = (np.asarray(right_position[:2]) + np.asarray(left_position[:2])) / 2.0
    if np.hypot(*c) < 1e-12:
        return 0.0
    return float(math.atan2(c[1], c[0]))


def _arm_constants():
    from maru_planner.robot import maru1_description as desc

    return desc.D_2, desc.L_3, desc.L_5, desc.L_6, desc.L_1


def _wrap_into(value: float, lo: float, hi: float, near: float) -> float | None:
    """value + 2*pi*k inside [lo, hi], the one closest to ``near``; None if none."""
    options = [value + 2 * math.pi * k for k in (-2, -1, 0, 1, 2)]
    inside = [v for v in options if lo - 1e-9 <= v <= hi + 1e-9]
    return min(inside, key=lambda v: abs(v - near)) if inside else None


def _elbow_points(S, W, a, r1, r2, elbow_hint):
    """Points E with |E-S| = r1, |W-E| = r2 and (W-E).a = 0 (eq. 11-14, solved exactly)."""
    n = W - S
    D = float(np.linalg.norm(n))
    if D < 1e-12 or D > r1 + r2 + 1e-12 or D < abs(r1 - r2) - 1e-12:
        return []
    n = n / D
    h = (D * D + r1 * r1 - r2 * r2) / (2 * D)
    rho = math.sqrt(max(r1 * r1 - h * h, 0.0))
    C = S + h * n
    e1 = np.cross(n, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 1e-6:
        e1 = np.cross(n, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    A, B, K = rho * float(e1 @ a), rho * float(e2 @ a), float((W - C) @ a)
    R = math.hypot(A, B)
    if R < 1e-12:  # hand axis along shoulder-wrist line: any elbow on the circle; take the one nearest the hint
        if abs(K) > 1e-9:
            return []
        d = elbow_hint - C
        d -= (d @ n) * n
        return [C + rho * d / np.linalg.norm(d)] if np.linalg.norm(d) > 1e-12 else [C + rho * e1]
    if abs(K) > R + 1e-12:
        return []
    base, spread = math.atan2(B, A), math.acos(max(-1.0, min(1.0, K / R)))
    return [C + rho * (math.cos(phi) * e1 + math.sin(phi) * e2) for phi in (base + spread, base - spread)]


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


_RX_MINUS = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # Rx(-pi/2)
_RX_PLUS = _RX_MINUS.T  # Rx(+pi/2)


def _arm_candidates(T: np.ndarray, side: str, seed_arm: np.ndarray) -> list[np.ndarray]:
    """All exact arm solutions (up to 8, unwrapped) for a hand pose T in the arm's mount frame."""
    d2, l3, l5, l6, l1 = _arm_constants()
    d1 = l1 if side == "r" else -l1
    S = np.array([0.0, 0.0, d1])
    R_h, p_h = T[:3, :3], T[:3, 3]
    a = R_h[:, 2]  # approach: joint 6 axis = z of the hand frame
    W = p_h - l6 * R_h[:, 0]  # eq. 9-10
    r1 = math.hypot(d2, l3)
    hint = _arm_point(seed_arm, S, d2, l3)
    solutions = []
    for E in _elbow_points(S, W, a, r1, l5, hint):
        v = E - S
        c2 = max(-1.0, min(1.0, v[2] / l3))
        for t2 in (math.acos(c2), -math.acos(c2)):
            t1 = math.atan2(v[1], v[0]) - math.atan2(d2, l3 * math.sin(t2))
            R2 = _rz(t1) @ _RX_MINUS @ _rz(t2) @ _RX_PLUS
            u = R2.T @ ((W - E) / l5)  # forearm direction = (c3 s4, s3 s4, c4) in frame 2
            c4 = max(-1.0, min(1.0, u[2]))
            for t4 in (math.acos(c4), -math.acos(c4)):
                s4 = math.sin(t4)
                t3 = math.atan2(u[1] / s4, u[0] / s4) if abs(s4) > 1e-9 else seed_arm[2]
                R4 = R2 @ _rz(t3) @ _RX_MINUS @ _rz(t4) @ _RX_PLUS
                M = R4.T @ R_h  # = Rz(t5) Rx(-pi/2) Rz(t6)
                t5 = math.atan2(-M[0, 2], M[1, 2])
                t6 = math.atan2(-M[2, 0], -M[2, 1])
                solutions.append(np.array([t1, t2, t3, t4, t5, t6]))
    return solutions


def _arm_point(arm: np.ndarray, S, d2, l3) -> np.ndarray:
    """Elbow position for arm angles (used as a hint for degenerate cases)."""
    t1, t2 = arm[0], arm[1]
    z1 = np.array([-math.sin(t1), math.cos(t1), 0.0])
    z2 = np.array([math.cos(t1) * math.sin(t2), math.sin(t1) * math.sin(t2), math.cos(t2)])
    return S + d2 * z1 + l3 * z2


def arm_ik_closed_form(
    robot: RobotModel,
    side: str,
    target: np.ndarray,
    q_seed: np.ndarray,
    *,
    tol: float = 1e-9,
    all_solutions: bool = False,
    is_valid: Validity | None = None,
):
    """Exact IK of one Maru-1 arm ('r' or 'l') for a hand pose (4x4, base_link); waist from q_seed.

    Returns the full configuration closest to the seed (or, with
    ``all_solutions``, every solution within limits, closest first) whose FK
    matches the target to ``tol``. Raises NoIKSolution otherwise.
    """
    if side not in ("r", "l"):
        raise InvalidRequest(f"side must be 'r' or 'l', got {side!r}")
    mount = f"{side}_arm_mount"
    if not robot.model.existFrame(mount):
        raise InvalidRequest(f"closed-form arm IK needs the Maru-1 model (no frame {mount!r} in {robot.name})")
    q_seed = np.asarray(q_seed, dtype=float)
    idx = robot.group_joint_indices("right_arm" if side == "r" else "left_arm")
    T_mount = robot.frame_pose(q_seed, mount)
    T_local = np.linalg.inv(T_mount) @ np.asarray(target, dtype=float)
    lo, hi = robot.lower_limits[idx], robot.upper_limits[idx]
    found = []
    for arm in _arm_candidates(T_local, side, q_seed[idx]):
        wrapped = [_wrap_into(v, lo[i], hi[i], q_seed[idx][i]) for i, v in enumerate(arm)]
        if any(v is None for v in wrapped):
            continue
        q = q_seed.copy()
        q[idx] = wrapped
        error = np.abs(robot.frame_pose(q, f"{side}_hand") - target).max()
        if error <= tol and (is_valid is None or is_valid(q)):
            found.append(q)
    found.sort(key=lambda q: float(np.linalg.norm(q[idx] - q_seed[idx])))
    if not found:
        raise NoIKSolution(f"no closed-form IK solution for {side}_hand within joint limits (or reach)")
    return found if all_solutions else found[0]


def _maru_arm_closed_form(robot, targets, q_seed, group, is_valid) -> np.ndarray | None:
    """Exact answer when the request is one Maru-1 hand with its own arm group; None if not applicable."""
    if len(targets) != 1 or group not in ("right_arm", "left_arm"):
        return None
    side = group[0]
    ((frame, target),) = targets.items()
    if frame != f"{side}_hand" or not robot.model.existFrame(f"{side}_arm_mount"):
        return None
    try:
        return arm_ik_closed_form(robot, side, target, np.asarray(q_seed, dtype=float), is_valid=is_valid)
    except NoIKSolution:
        return None


def two_hand_ik(
    robot: RobotModel,
    right_target: np.ndarray,
    left_target: np.ndarray,
    q_seed: np.ndarray,
    *,
    tol: float = 1e-6,
    max_restarts: int = 20,
    rng: np.random.Generator | None = None,
    deadline: float | None = None,
    is_valid: Validity | None = None,
    waist_step: float = 0.05,
) -> np.ndarray:
    """Paper 000 sec. III.2.2 for Maru-1: waist from the hands' midpoint (eq. 5-6), then each arm (eq. 7-8).

    Each arm is solved in closed form (solutions closest to the seed first).
    Where an arm cannot reach at the eq. 6 angle (joint limits), the waist
    angles next to it are tried outward in ``waist_step`` increments; if none
    works, the numeric IK solves both hands over the whole upper body.
    """
    q_seed = np.asarray(q_seed, dtype=float)
    waist = int(robot.group_joint_indices("upper_body")[0])
    lo, hi = robot.lower_limits[waist], robot.upper_limits[waist]
    theta = float(np.clip(waist_angle_from_hands(right_target[:3, 3], left_target[:3, 3]), lo, hi))
    l_idx = robot.group_joint_indices("left_arm")
    for angle in _outward(theta, lo, hi, waist_step):
        if deadline is not None and time.monotonic() > deadline:
            break
        q = q_seed.copy()
        q[waist] = angle
        try:
            right = arm_ik_closed_form(robot, "r", right_target, q, all_solutions=True)
            left = arm_ik_closed_form(robot, "l", left_target, q, all_solutions=True)
        except NoIKSolution:
            continue
        for qr in right:
            for ql in left:
                candidate = qr.copy()
                candidate[l_idx] = ql[l_idx]
                if is_valid is None or is_valid(candidate):
                    return candidate
    q = q_seed.copy()
    q[waist] = theta
    targets = {"r_hand": right_target, "l_hand": left_target}
    return solve_ik(
        robot,
        targets,
        q,
        "upper_body",
        tol=tol,
        max_restarts=max_restarts,
        rng=rng,
        deadline=deadline,
        is_valid=is_valid,
    )


def _outward(center: float, lo: float, hi: float, step: float):
    """center, center +- step, center +- 2 step, ... inside [lo, hi]."""
    yield center
    k = 1
    while center - k * step >= lo or center + k * step <= hi:
        for value in (center + k * step, center - k * step):
            if lo <= value <= hi:
                yield value
        k += 1
