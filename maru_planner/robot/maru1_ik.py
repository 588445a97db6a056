"""Maru-1's IK strategies (its robot profile lists them): paper 000's closed-form arms and two-hand scheme.

- ``arm_ik_closed_form``: exact geometric 6-DOF arm IK, following sec. III.2.2 (wrist point, elbow on
  two spheres and a plane, then theta1..theta6) with the printed formulas' errors fixed (docs/robot.md).
- ``two_hand_ik``: the paper's scheme: waist angle from the two hand targets (eq. 5-6), then each arm
  on its own (eq. 7-8).
- ``one_arm_strategy`` and ``two_hands_strategy``: the two as :class:`~maru_planner.robot.ik.IKStrategy`,
  for the requests they answer (one hand with its own arm group; both hands over ``upper_body``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from maru_planner.errors import InvalidRequest, NoIKSolution
from maru_planner.robot import maru1_description as desc
from maru_planner.robot.ik import Validity, solve_ik_numeric, wrap_into

if TYPE_CHECKING:  # annotations only: model.py imports the profiles, which import this module
    from maru_planner.robot.model import RobotModel

ARM_GROUPS = {"right_arm": "r", "left_arm": "l"}
BOTH_HANDS_GROUP = "upper_body"


def one_arm_strategy(
    robot: RobotModel,
    targets: Mapping[str, np.ndarray],
    q_seed: np.ndarray,
    group: str | None,
    *,
    deadline: float | None = None,
    is_valid: Validity | None = None,
) -> np.ndarray | None:
    """Closed form for one hand with its own arm group (``right_arm`` + ``r_hand``); None otherwise."""
    side = ARM_GROUPS.get(group or "")
    if side is None or set(targets) != {f"{side}_hand"}:
        return None
    return arm_ik_closed_form(robot, side, targets[f"{side}_hand"], q_seed, is_valid=is_valid)


def two_hands_strategy(
    robot: RobotModel,
    targets: Mapping[str, np.ndarray],
    q_seed: np.ndarray,
    group: str | None,
    *,
    deadline: float | None = None,
    is_valid: Validity | None = None,
) -> np.ndarray | None:
    """The paper's two-hand scheme for both hands over ``upper_body``; None for other requests."""
    if group != BOTH_HANDS_GROUP or set(targets) != {"r_hand", "l_hand"}:
        return None
    return two_hand_ik(robot, targets["r_hand"], targets["l_hand"], q_seed, deadline=deadline, is_valid=is_valid)


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
    d2, l3, l5, l6, l1 = desc.D_2, desc.L_3, desc.L_5, desc.L_6, desc.L_1
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
        wrapped = [wrap_into(v, lo[i], hi[i], q_seed[idx][i]) for i, v in enumerate(arm)]
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
    return solve_ik_numeric(
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
