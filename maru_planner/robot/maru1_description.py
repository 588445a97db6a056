"""Maru-1 upper body (paper 000, Table 1): the one place its numbers live.

Generates ``urdf/maru1_upper_body.urdf`` and ``urdf/maru1_upper_body.srdf``::

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
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from maru_planner.paths import urdf_path
from maru_planner.robot.disabled_collisions import compute_disabled_collisions
from maru_planner.scene import matrix_rpy

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
ACCELERATION_LIMIT = 4.0  # rad/s^2, all joints (URDF has no field for it)


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


if __name__ == "__main__":
    raise SystemExit(main())
