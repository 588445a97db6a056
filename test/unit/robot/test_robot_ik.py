"""IK: closed-form Maru-1 arm, the paper's two-hand scheme, numeric DLS; round trips FK -> IK -> FK."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.errors import InvalidGroup, NoIKSolution
from maru_planner.robot import RobotModel
from maru_planner.robot.ik import solve_ik
from maru_planner.robot.robots.maru1 import arm_ik_closed_form, two_hand_ik, waist_angle_from_hands

START13 = np.array([-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25])


@pytest.fixture(scope="module")
def robot():
    return RobotModel.maru1()


def pose_error(robot, q, frame, target):
    return np.abs(robot.frame_pose(q, frame) - target).max()


@pytest.mark.parametrize("side", ["r", "l"])
def test_closed_form_arm_recovers_every_configuration(robot, side):
    rng = np.random.default_rng(10)
    idx = robot.group_joint_indices("right_arm" if side == "r" else "left_arm")
    for _ in range(100):
        q = robot.random_configuration(rng)
        target = robot.frame_pose(q, f"{side}_hand")
        solutions = arm_ik_closed_form(robot, side, target, q, all_solutions=True)
        for s in solutions:
            assert pose_error(robot, s, f"{side}_hand", target) < 1e-9 and robot.within_limits(s)
        assert min(np.abs(s[idx] - q[idx]).max() for s in solutions) < 1e-8  # the original is among them
        assert np.abs(solutions[0][idx] - q[idx]).max() < 1e-8  # and closest to the seed


def test_waist_angle_is_the_midpoint_direction():
    assert waist_angle_from_hands([0.4, -0.2, 0], [0.4, 0.2, 0]) == pytest.approx(0.0)
    assert waist_angle_from_hands([0.3, 0.1, 0], [0.1, 0.3, 0]) == pytest.approx(np.pi / 4)


def test_two_hand_round_trip(robot):
    rng = np.random.default_rng(11)
    for _ in range(40):
        q = robot.random_configuration(rng)
        right, left = robot.frame_pose(q, "r_hand"), robot.frame_pose(q, "l_hand")
        sol = two_hand_ik(robot, right, left, robot.neutral(), rng=rng)
        assert pose_error(robot, sol, "r_hand", right) < 1e-6
        assert pose_error(robot, sol, "l_hand", left) < 1e-6
        assert robot.within_limits(sol)


def test_two_hand_on_paper_start_searches_from_eq6_waist(robot):
    right, left = robot.frame_pose(START13, "r_hand"), robot.frame_pose(START13, "l_hand")
    eq6 = waist_angle_from_hands(right[:3, 3], left[:3, 3])
    sol = two_hand_ik(robot, right, left, START13 * 0.9, waist_step=0.05)
    assert abs(sol[0] - eq6) == pytest.approx(0.1)  # eq. 6 gives -0.80: the arms reach from 2 steps away
    assert sol[0] == pytest.approx(-0.9, abs=0.01)  # the paper's own start value


@pytest.mark.parametrize("group, frames", [("torso_right_arm", ["r_hand"]), ("upper_body", ["r_hand", "l_hand"])])
def test_numeric_round_trip(robot, group, frames):
    rng = np.random.default_rng(12)
    for _ in range(15):
        q = robot.random_configuration(rng)
        targets = {f: robot.frame_pose(q, f) for f in frames}
        sol = solve_ik(robot, targets, robot.neutral(), group, rng=rng)
        assert all(pose_error(robot, sol, f, t) < 1e-6 for f, t in targets.items())
        assert robot.within_limits(sol)


def test_group_joints_only_move(robot):
    rng = np.random.default_rng(13)
    q = robot.random_configuration(rng)
    seed = robot.neutral()
    seed[0] = q[0]
    sol = solve_ik(robot, {"r_hand": robot.frame_pose(q, "r_hand")}, seed, "right_arm")
    others = np.setdiff1d(np.arange(robot.nq), robot.group_joint_indices("right_arm"))
    np.testing.assert_array_equal(sol[others], seed[others])


def test_unreachable_targets_raise(robot):
    far = np.eye(4)
    far[:3, 3] = [1.5, -0.2, 0.3]
    with pytest.raises(NoIKSolution, match="r_hand"):
        solve_ik(robot, {"r_hand": far}, robot.neutral(), "torso_right_arm", max_restarts=3)
    with pytest.raises(NoIKSolution, match="closed-form"):
        arm_ik_closed_form(robot, "r", far, robot.neutral())
    with pytest.raises(NoIKSolution):
        two_hand_ik(robot, far, far, robot.neutral(), max_restarts=2)
    with pytest.raises(InvalidGroup):
        solve_ik(robot, {"r_hand": far}, robot.neutral(), "no_group")


def test_validity_callback_rejects_solutions(robot):
    q = robot.named_state("home")
    target = robot.frame_pose(q, "r_hand")
    with pytest.raises(NoIKSolution):
        solve_ik(robot, {"r_hand": target}, q, "torso_right_arm", max_restarts=2, is_valid=lambda _q: False)


def test_a_damped_system_singular_to_machine_precision_is_no_solution_not_a_crash(robot, monkeypatch):
    """bench/robustness.py: compute_ik answered INTERNAL_ERROR ('LinAlgError: Singular matrix') for hostile goals."""
    from maru_planner.robot import ik

    def singular(*_args):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(ik.np.linalg, "solve", singular)
    far = np.eye(4)
    far[:3, 3] = [0.4, -0.2, 0.3]
    with pytest.raises(NoIKSolution, match="r_hand"):
        ik.solve_ik_numeric(robot, {"r_hand": far}, robot.neutral(), "torso_right_arm", max_restarts=1)
