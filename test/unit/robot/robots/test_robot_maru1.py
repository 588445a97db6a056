"""Maru-1 model: names, groups, limits, FK against an independent DH chain of Table 1."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.errors import InvalidGroup
from maru_planner.paths import urdf_path
from maru_planner.robot import RobotModel
from maru_planner.robot.robots import maru1 as desc

ORDER = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
START6 = [0, 1.57, 1.57, 0, -1.57, -1.57]
GOAL6 = [-1.57, 1.57, 1.57, 0, -1.57, -1.57]
START13 = [-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25]
GOAL13 = [0.9, -0.8, 1.57, 1.14, 0.7, -1.24, -1.9, -0.7, 1.57, 2.44, 0.7, -2.24, -1.25]


@pytest.fixture(scope="module")
def robot():
    return RobotModel.maru1()


def dh(theta, d, a, alpha):
    """Independent standard-DH matrix Rz(theta) Tz(d) Tx(a) Rx(alpha)."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])


def table_hand_pose(waist, arm, side):
    """Hand pose from Table 1 written out row by row (left as printed, right with +l0, +l1)."""
    s = 1.0 if side == "r" else -1.0
    h = np.pi / 2
    T = dh(waist, 0.284, 0.04, h) @ dh(0.0, s * 0.1615, 0, 0)
    rows = [(s * 0.061, 0, -h), (0.0055, 0, h), (0.224, 0, -h), (0, 0, h), (0.225, 0, -h), (0, 0.041, 0)]
    for theta, (d, a, alpha) in zip(arm, rows):
        T = T @ dh(theta, d, a, alpha)
    return T


def eq4_position(q):
    """Paper 000 eq. 4 (hand position in the shoulder frame), as printed."""
    S1, S2, S3, S4, S5, S6 = np.sin(q)
    C1, C2, C3, C4, C5, C6 = np.cos(q)
    d2, l3, l5, l6 = 0.0055, 0.224, 0.225, 0.041
    A = C1 * C2 * C3 - S1 * S3
    B = C2 * C3 * S1 + C1 * S3
    px = (
        -d2 * S1
        + C1 * l3 * S2
        + l6 * S6 * (-C1 * C4 * S2 - A * S4)
        + l5 * (C1 * C4 * S2 + A * S4)
        + l6 * C6 * (C5 * (C4 * A - C1 * S2 * S4) + (-C3 * S1 - C1 * C2 * S3) * S5)
    )
    py = (
        C1 * d2
        + l3 * S1 * S2
        + l6 * S6 * (-C4 * S1 * S2 - B * S4)
        + l5 * (C4 * S1 * S2 + B * S4)
        + l6 * C6 * (C5 * (C4 * B - S1 * S2 * S4) + (C1 * C3 - C2 * S1 * S3) * S5)
    )
    pz = (
        C2 * l3
        + l5 * (C2 * C4 - C3 * S2 * S4)
        + l6 * S6 * (-C2 * C4 + C3 * S2 * S4)
        + l6 * C6 * (C5 * (-C3 * C4 * S2 - C2 * S4) + S2 * S3 * S5)
    )
    return np.array([px, py, pz])


def test_joint_order_and_frames(robot):
    assert robot.joint_names == ORDER
    assert robot.nq == 13
    assert robot.end_effectors == {"right": "r_hand", "left": "l_hand"}
    assert robot.model.frames[robot.frame_id("base_link")].parentJoint == 0


def test_groups(robot):
    assert set(robot.groups) == {"upper_body", "right_arm", "left_arm", "torso_right_arm", "torso_left_arm"}
    assert robot.groups["upper_body"] == ORDER
    np.testing.assert_array_equal(robot.group_joint_indices("right_arm"), np.arange(1, 7))
    np.testing.assert_array_equal(robot.group_joint_indices("torso_left_arm"), [0, 7, 8, 9, 10, 11, 12])
    with pytest.raises(InvalidGroup, match="no_such_group"):
        robot.group_joint_indices("no_such_group")


def test_limits_contain_paper_states(robot):
    for q in (START13, GOAL13, [0, *START6, *GOAL6], [0, *GOAL6, *GOAL6]):
        assert robot.within_limits(np.array(q)), q
    assert np.all(robot.velocity_limits > 0) and np.all(robot.acceleration_limits > 0)
    n = robot.neutral()
    assert robot.within_limits(n) and n.shape == (13,)


def test_fk_matches_table_dh(robot):
    rng = np.random.default_rng(1)
    for _ in range(250):
        q = robot.random_configuration(rng)
        for side, arm in (("r", q[1:7]), ("l", q[7:13])):
            expected = table_hand_pose(q[0], arm, side)
            np.testing.assert_allclose(robot.frame_pose(q, f"{side}_hand"), expected, atol=1e-9)


def test_fk_matches_paper_eq4_in_shoulder_frame(robot):
    rng = np.random.default_rng(2)
    for _ in range(50):
        q = robot.random_configuration(rng)
        for side, arm in (("r", q[1:7]), ("l", q[7:13])):
            T_s = robot.frame_pose(q, f"{side}_shoulder")
            T_h = robot.frame_pose(q, f"{side}_hand")
            np.testing.assert_allclose((np.linalg.inv(T_s) @ T_h)[:3, 3], eq4_position(arm), atol=1e-9)


def test_paper_task_meaning(robot):
    """Under eq. 4's zero, the 6-DOF start is the arm stretched forward and the goal hangs down."""
    q = np.array([0, *START6, *GOAL6])
    hand = robot.frame_pose(q, "r_hand")[:3, 3]
    assert hand[0] > 0.5 and abs(hand[2] - 0.289) < 0.01
    q = np.array([0, *GOAL6, *GOAL6])
    assert robot.frame_pose(q, "r_hand")[2, 3] < -0.2
    assert robot.frame_pose(np.array(START13), "r_hand")[1, 3] < -0.2  # both hands start on the right
    assert robot.frame_pose(np.array(GOAL13), "l_hand")[1, 3] > 0.2  # and end on the left


def test_jacobian_matches_finite_difference(robot):
    rng = np.random.default_rng(3)
    q = robot.random_configuration(rng)
    J = robot.frame_jacobian(q, "r_hand")
    eps = 1e-7
    for i in range(robot.nq):
        dq = np.zeros(robot.nq)
        dq[i] = eps
        dp = (robot.frame_pose(q + dq, "r_hand")[:3, 3] - robot.frame_pose(q - dq, "r_hand")[:3, 3]) / (2 * eps)
        np.testing.assert_allclose(J[:3, i], dp, atol=1e-6)


def test_checked_in_files_match_generator():
    urdf_dir = urdf_path()
    assert (urdf_dir / "maru1_upper_body.urdf").read_text() == desc.generate_urdf()
    srdf = (urdf_dir / "maru1_upper_body.srdf").read_text()
    assert 'reason="Adjacent"' in srdf and 'reason="Never"' in srdf
    assert '<disable_collisions link1="r_arm_link5" link2="l_arm_link5"' not in srdf  # forearms can meet
