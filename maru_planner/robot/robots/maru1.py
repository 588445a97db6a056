"""Maru-1 upper body (paper 000, Table 1): the one place its numbers live.

The robot's module: its description (Table 1, limits, collision geometry, the generated URDF/SRDF),
its closed-form IK (paper 000 sec. III.2.2) and its :data:`PROFILE`. Generates
``urdf/maru1_upper_body.urdf`` and ``urdf/maru1_upper_body.srdf`` (through the old module's path,
which the files' header names)::

    python -m maru_planner.robot.maru1_description          # regenerate both
    python -m maru_planner.robot.maru1_description --check  # exit 1 if the files are stale

Kinematic convention: standard DH, ``Rz(theta + theta0) Tz(d) Tx(a) Rx(alpha)``
per row. The root ``base_link`` is the paper's body frame B (x forward, y
left, z up). Left arm = Table 1 as printed (``U-J0 d = -l0``, ``L1 d = -l1``);
the right arm uses the same rows with ``+l0`` and ``+l1``.

theta0: Table 1 prints an offset column, but the paper's own closed-form
forward kinematics (eq. 4) is the product A1...A6 *without* those offsets, and
the experiment configurations only mean what the text says under eq. 4: with
(0, 1.57, 1.57, 0, -1.57, -1.57) the arm is stretched forward and with
(-1.57, 1.57, ...) it hangs down. With the printed offsets the same start would
put the right wrist inside the left shoulder. So the joint zero used here is
eq. 4's: ``theta0 = 0`` for every row (the printed column is kept in
``PRINTED_THETA0`` for reference). See docs/robot.md.

The URDF mirrors the DH chain exactly: joint i rotates about z of DH frame
i-1, and the constant part of row i becomes the origin of joint i+1. Fixed
frames ``r_shoulder``/``l_shoulder`` are the paper's shoulder frames RS/LS
(eq. 1-2, at waist angle 0); ``r_hand``/``l_hand`` are the frames after L6.

IK strategies (the profile lists them, tried before the numeric IK):

- ``arm_ik_closed_form``: exact geometric 6-DOF arm IK, following sec. III.2.2 (wrist point, elbow on
  two spheres and a plane, then theta1..theta6) with the printed formulas' errors fixed (docs/robot.md).
- ``two_hand_ik``: the paper's scheme: waist angle from the two hand targets (eq. 5-6), then each arm
  on its own (eq. 7-8).
- ``one_arm_strategy`` and ``two_hands_strategy``: the two as :class:`~maru_planner.robot.ik.IKStrategy`,
  for the requests they answer (one hand with its own arm group; both hands over ``upper_body``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from maru_planner.errors import InvalidRequest, NoIKSolution
from maru_planner.paths import urdf_path
from maru_planner.robot.disabled_collisions import compute_disabled_collisions
from maru_planner.robot.ik import Validity, solve_ik_numeric, wrap_into
from maru_planner.robot.model import RobotModel
from maru_planner.robot.profile_yaml import load_profile
from maru_planner.scene.poses import matrix_rpy

# ---------------------------------------------------------------- Table 1 ----
L_U = 0.284  # body origin -> upper body frame U, along z
D_U = 0.04  # body origin -> U, along x
L_0 = 0.1615  # U -> J0 (half shoulder width, part 1)
L_1 = 0.061  # J0 -> shoulder centre
D_2 = 0.0055  # small shoulder offset
L_3 = 0.224  # upper arm
L_5 = 0.225  # forearm
L_6 = 0.041  # wrist -> hand frame

HALF_PI = math.pi / 2
PRINTED_THETA0 = (-HALF_PI, HALF_PI, HALF_PI, 0.0, -HALF_PI, -HALF_PI)  # L1..L6, not used (see module doc)


@dataclass(frozen=True)
class DHRow:
    """One standard-DH row; ``joint`` is None for a fixed row (theta = 0)."""

    joint: str | None
    d: float
    a: float
    alpha: float
    theta0: float = 0.0

    @property
    def revolute_joint(self) -> str:
        """The joint's name; ValueError for a fixed row."""
        if self.joint is None:
            raise ValueError("a fixed DH row has no joint")
        return self.joint


def body_row() -> DHRow:
    return DHRow("waist_yaw", L_U, D_U, HALF_PI)


def arm_rows(side: str) -> list[DHRow]:
    """Rows U-J0, L1..L6 of one arm; ``side`` is 'r' or 'l'."""
    if side not in ("r", "l"):
        raise ValueError(f"side must be 'r' or 'l', got {side!r}")
    s = 1.0 if side == "r" else -1.0
    p = f"{side}_arm_j"
    return [
        DHRow(None, s * L_0, 0.0, 0.0),
        DHRow(p + "1", s * L_1, 0.0, -HALF_PI),
        DHRow(p + "2", D_2, 0.0, HALF_PI),
        DHRow(p + "3", L_3, 0.0, -HALF_PI),
        DHRow(p + "4", 0.0, 0.0, HALF_PI),
        DHRow(p + "5", L_5, 0.0, -HALF_PI),
        DHRow(p + "6", 0.0, L_6, 0.0),
    ]


def dh_matrix(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH transform ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d], [0.0, 0.0, 0.0, 1.0]]
    )


# ------------------------------------------------------------ joint limits ----
# Not in the paper. Humanoid ranges in this file's joint zero (eq. 4), chosen
# to contain the paper's start/goal states with margin; the left arm mirrors
# the right (same axes, shoulder on the other side): left j2 = pi - right j2.
# (lower, upper, velocity rad/s). Reasons in docs/robot.md.
JOINT_LIMITS: dict[str, tuple[float, float, float]] = {
    "waist_yaw": (-1.57, 1.57, 1.0),
    "j1": (-2.6, 1.6, 2.0),  # shoulder pitch: 0 = arm forward, -pi/2 = down, +pi/2 = up
    "r_j2": (-0.5, 2.5, 2.0),  # shoulder yaw: 0 = arm out to the side, pi/2 = forward
    "l_j2": (math.pi - 2.5, math.pi + 0.5, 2.0),
    "j3": (HALF_PI - 1.7, HALF_PI + 1.7, 2.5),  # upper-arm roll, centred on pi/2
    "j4": (-0.1, 2.6, 2.5),  # elbow, 0 = straight
    "j5": (-HALF_PI - 1.65, -HALF_PI + 1.65, 3.0),  # forearm roll, centred on -pi/2
    "j6": (-HALF_PI - 1.4, -HALF_PI + 1.4, 3.0),  # wrist, centred on -pi/2
}
EFFORT = 30.0


def joint_limit(name: str) -> tuple[float, float, float]:
    if name == "waist_yaw":
        return JOINT_LIMITS[name]
    side, index = name[0], name[-1]
    key = f"{side}_j2" if index == "2" else f"j{index}"
    return JOINT_LIMITS[key]


# ------------------------------------------------------ collision geometry ----
# Sizes for a 150 cm humanoid. base_link (waist joint) is ~0.94 m above the
# floor, shoulders 0.284 m above it, head top ~0.55 m above it.
# Each entry: (link, kind, dims, xyz, rpy); cylinders are along local z.
def collision_geometry(side_links: dict[str, list[str]]) -> list[tuple[str, str, tuple, tuple, tuple]]:
    shapes: list[tuple[str, str, tuple, tuple, tuple]] = [
        ("base_link", "box", (0.18, 0.26, 0.29), (0.0, 0.0, -0.155), (0, 0, 0)),  # pelvis + hips
        ("torso", "box", (0.19, 0.26, 0.20), (0.015, 0.0, 0.14), (0, 0, 0)),  # chest
        ("torso", "box", (0.13, 0.28, 0.06), (0.0, 0.0, 0.27), (0, 0, 0)),  # shoulder yoke
        ("torso", "cylinder", (0.045, 0.08), (-0.01, 0.0, 0.34), (0, 0, 0)),  # neck
        ("torso", "sphere", (0.10,), (-0.01, 0.0, 0.45), (0, 0, 0)),  # head
    ]
    for side, links in side_links.items():
        s = 1.0 if side == "r" else -1.0
        shapes += [
            (links[0], "cylinder", (0.045, L_1), (0.0, 0.0, s * L_1 / 2), (0, 0, 0)),  # shoulder block
            (links[1], "sphere", (0.05,), (0.0, 0.0, 0.0), (0, 0, 0)),  # shoulder ball
            (links[2], "cylinder", (0.04, L_3), (0.0, 0.0, L_3 / 2), (0, 0, 0)),  # upper arm
            (links[3], "sphere", (0.042,), (0.0, 0.0, 0.0), (0, 0, 0)),  # elbow
            (links[4], "cylinder", (0.036, L_5), (0.0, 0.0, L_5 / 2), (0, 0, 0)),  # forearm
            (f"{side}_hand", "box", (0.11, 0.035, 0.075), (0.014, 0.0, 0.0), (0, 0, 0)),  # hand, along x
        ]
    return shapes


# ------------------------------------------------------------------ URDF ----
def _num(x: float) -> str:
    x = 0.0 if abs(x) < 1e-15 else float(x)
    return repr(x)


def _origin(T: np.ndarray) -> str:
    xyz = " ".join(_num(v) for v in T[:3, 3])
    rpy = " ".join(_num(v) for v in matrix_rpy(T[:3, :3]))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _geometry_xml(kind: str, dims: tuple) -> str:
    if kind == "box":
        return f'<box size="{" ".join(_num(v) for v in dims)}"/>'
    if kind == "sphere":
        return f'<sphere radius="{_num(dims[0])}"/>'
    return f'<cylinder radius="{_num(dims[0])}" length="{_num(dims[1])}"/>'


def _link_xml(name: str, shapes: list, mass: float) -> str:
    parts = [f"  <link name={quoteattr(name)}>"]
    if mass > 0:
        parts.append(
            f'    <inertial><mass value="{mass}"/><origin xyz="0 0 0"/>'
            f'<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>'
        )
    for _, kind, dims, xyz, rpy in shapes:
        T = np.eye(4)
        T[:3, 3] = xyz
        assert rpy == (0, 0, 0)
        body = f"{_origin(T)}<geometry>{_geometry_xml(kind, dims)}</geometry>"
        parts.append(f"    <visual>{body}</visual>")
        parts.append(f"    <collision>{body}</collision>")
    parts.append("  </link>")
    return "\n".join(parts)


def _joint_xml(name: str, parent: str, child: str, T: np.ndarray, revolute: bool) -> str:
    lines = [f'  <joint name={quoteattr(name)} type="{"revolute" if revolute else "fixed"}">']
    lines.append(f"    <parent link={quoteattr(parent)}/><child link={quoteattr(child)}/>")
    lines.append(f"    {_origin(T)}")
    if revolute:
        lo, hi, vel = joint_limit(name)
        lines.append('    <axis xyz="0 0 1"/>')
        lines.append(f'    <limit lower="{_num(lo)}" upper="{_num(hi)}" effort="{EFFORT}" velocity="{_num(vel)}"/>')
    lines.append("  </joint>")
    return "\n".join(lines)


MOUNT_JOINTS = {"r": "arm_mount_1_right", "l": "arm_mount_2_left"}


def _arm_links(side: str) -> list[str]:
    return [f"{side}_arm_link{i}" for i in range(1, 7)]


def generate_urdf() -> str:
    """The URDF text of the Maru-1 upper body."""
    side_links = {"r": _arm_links("r"), "l": _arm_links("l")}
    shapes = collision_geometry(side_links)
    links_xml: list[str] = []
    joints_xml: list[str] = []

    def add_link(name: str, mass: float = 0.5) -> None:
        links_xml.append(_link_xml(name, [s for s in shapes if s[0] == name], mass))

    add_link("base_link", 0.0)
    body = body_row()
    joints_xml.append(_joint_xml(body.revolute_joint, "base_link", "torso", dh_matrix(body.theta0, 0, 0, 0), True))
    add_link("torso", 5.0)
    body_const = dh_matrix(0.0, body.d, body.a, body.alpha)
    for side in ("r", "l"):
        rows = arm_rows(side)
        shoulder = body_const @ dh_matrix(0.0, rows[0].d, 0.0, 0.0) @ dh_matrix(0.0, rows[1].d, 0.0, 0.0)
        joints_xml.append(_joint_xml(f"{side}_shoulder_joint", "torso", f"{side}_shoulder", shoulder, False))
        add_link(f"{side}_shoulder", 0.0)
        # The arm hangs off a fixed mount link (DH frame J0). urdfdom orders a link's children by joint
        # name, so these names make Pinocchio's q order waist, right arm, left arm (the paper's order).
        mount = body_const @ dh_matrix(rows[0].theta0, rows[0].d, rows[0].a, rows[0].alpha)
        joints_xml.append(_joint_xml(MOUNT_JOINTS[side], "torso", f"{side}_arm_mount", mount, False))
        add_link(f"{side}_arm_mount", 0.0)
        parent, pending = f"{side}_arm_mount", np.eye(4)
        for row, link in zip(rows[1:], side_links[side]):
            origin = pending @ dh_matrix(row.theta0, 0, 0, 0)
            joints_xml.append(_joint_xml(row.revolute_joint, parent, link, origin, True))
            add_link(link)
            parent, pending = link, dh_matrix(0.0, row.d, row.a, row.alpha)
        joints_xml.append(_joint_xml(f"{side}_hand_joint", parent, f"{side}_hand", pending, False))
        add_link(f"{side}_hand", 0.0)
    header = (
        '<?xml version="1.0"?>\n'
        "<!-- GENERATED by `python -m maru_planner.robot.maru1_description` from paper 000 Table 1. "
        "Do not edit by hand. -->\n"
        '<robot name="maru1_upper_body">'
    )
    return "\n".join([header, *links_xml, *joints_xml, "</robot>"]) + "\n"


# ------------------------------------------------------------------ SRDF ----
ARM_JOINTS = {side: [f"{side}_arm_j{i}" for i in range(1, 7)] for side in ("r", "l")}
GROUPS: dict[str, list[str]] = {
    "right_arm": ARM_JOINTS["r"],
    "left_arm": ARM_JOINTS["l"],
    "torso_right_arm": ["waist_yaw", *ARM_JOINTS["r"]],
    "torso_left_arm": ["waist_yaw", *ARM_JOINTS["l"]],
    "upper_body": ["waist_yaw", *ARM_JOINTS["r"], *ARM_JOINTS["l"]],
}
ARM_DOWN = (-HALF_PI, HALF_PI, HALF_PI, 0.0, -HALF_PI, -HALF_PI)  # paper's 6-DOF goal: arm hanging down
NAMED_STATES = {
    "home": {"waist_yaw": 0.0, **dict(zip(ARM_JOINTS["r"], ARM_DOWN)), **dict(zip(ARM_JOINTS["l"], ARM_DOWN))}
}
DISABLED_PAIR_SAMPLES = 20000
DISABLED_PAIR_SEED = 7


def generate_srdf(disabled: list[tuple[str, str, str]]) -> str:
    """The SRDF text; ``disabled`` is a list of (link1, link2, reason)."""
    lines = ['<?xml version="1.0"?>', "<!-- GENERATED by `python -m maru_planner.robot.maru1_description`. -->"]
    lines.append('<robot name="maru1_upper_body">')
    for group, joints in GROUPS.items():
        lines.append(f'  <group name="{group}">')
        lines += [f'    <joint name="{j}"/>' for j in joints]
        lines.append("  </group>")
    for state, values in NAMED_STATES.items():
        lines.append(f'  <group_state name="{state}" group="upper_body">')
        lines += [f'    <joint name="{j}" value="{_num(v)}"/>' for j, v in values.items()]
        lines.append("  </group_state>")
    lines.append('  <end_effector name="right" parent_link="r_hand" group="right_arm"/>')
    lines.append('  <end_effector name="left" parent_link="l_hand" group="left_arm"/>')
    for a, b, reason in disabled:
        lines.append(f'  <disable_collisions link1="{a}" link2="{b}" reason="{reason}"/>')
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def generate(n_samples: int = DISABLED_PAIR_SAMPLES) -> tuple[str, str]:
    """(urdf_text, srdf_text); the SRDF's disabled pairs are computed by sampling."""
    urdf = generate_urdf()
    disabled = compute_disabled_collisions(urdf, n_samples=n_samples, seed=DISABLED_PAIR_SEED)
    return urdf, generate_srdf(disabled)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out-dir", type=Path, default=None, help="default: the package's urdf/ directory")
    parser.add_argument("--samples", type=int, default=DISABLED_PAIR_SAMPLES)
    parser.add_argument("--check", action="store_true", help="exit 1 if the checked-in files differ")
    args = parser.parse_args(argv)
    out_dir = args.out_dir or urdf_path()
    urdf, srdf = generate(args.samples)
    targets = {out_dir / "maru1_upper_body.urdf": urdf, out_dir / "maru1_upper_body.srdf": srdf}
    if args.check:
        stale = [str(p) for p, text in targets.items() if not p.is_file() or p.read_text() != text]
        print("stale: " + ", ".join(stale) if stale else "up to date")
        return 1 if stale else 0
    out_dir.mkdir(parents=True, exist_ok=True)
    for path, text in targets.items():
        path.write_text(text)
        print(f"wrote {path}", file=sys.stderr)
    return 0


# -------------------------------------------------------------------- IK ----
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
    d2, l3, l5, l6, l1 = D_2, L_3, L_5, L_6, L_1
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


# --------------------------------------------------------------- profile ----
PROFILE = load_profile(Path(__file__).with_suffix(".yaml"), check_files=False)  # maru1.yaml (names the IK above)
ACCELERATION_LIMIT = float(np.max(PROFILE.acceleration_limits))  # rad/s^2, all joints (URDF has no field for it)


if __name__ == "__main__":
    raise SystemExit(main())
