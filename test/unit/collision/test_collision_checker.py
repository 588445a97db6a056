"""CollisionChecker on Maru-1: paper scenes, self-collision, scene edits, batch checks."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.collision import CollisionChecker
from maru_planner.collision.kernels.bisection import bisection_order
from maru_planner.paths import config_path
from maru_planner.robot import RobotModel
from maru_planner.robot.robot_profile import example_robot_data_dir
from maru_planner.scene import Obstacle, Scene

DOWN = [-1.57, 1.57, 1.57, 0, -1.57, -1.57]
START6 = np.array([0, 0, 1.57, 1.57, 0, -1.57, -1.57, *DOWN])
GOAL6 = np.array([0, *DOWN, *DOWN])
START13 = np.array([-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25])
GOAL13 = np.array([0.9, -0.8, 1.57, 1.14, 0.7, -1.24, -1.9, -0.7, 1.57, 2.44, 0.7, -2.24, -1.25])


@pytest.fixture(scope="module")
def robot():
    return RobotModel.maru1()


@pytest.mark.parametrize(
    "scene_file, start, goal",
    [("maru6_desk.yaml", START6, GOAL6), ("maru13_desk_box.yaml", START13, GOAL13)],
)
def test_paper_task_endpoints_free_and_straight_line_blocked(robot, scene_file, start, goal):
    cc = CollisionChecker(robot, Scene.from_yaml(config_path("scenes", scene_file)))
    assert cc.is_valid(start), cc.colliding_pairs(start)
    assert cc.is_valid(goal), cc.colliding_pairs(goal)
    assert cc.clearance(start) > 0.01 and cc.clearance(goal) > 0.01
    line = np.linspace(start, goal, 201)
    assert cc.first_invalid(line) > 0
    hits = {pair for q in line[~cc.are_valid(line)] for pair in cc.colliding_pairs(q)}
    assert any(obstacle in ("desk", "box") for _, obstacle in hits)


def test_self_collision_is_detected_and_srdf_filters_adjacent(robot):
    cc = CollisionChecker(robot)
    left_arm_through_chest = robot.neutral()  # left j2 clipped to its lower limit: arm across the body
    assert not cc.is_valid(left_arm_through_chest)
    assert ("torso", "l_arm_link3") in cc.colliding_pairs(left_arm_through_chest)
    home = robot.named_state("home")
    assert cc.is_valid(home) and cc.colliding_pairs(home) == []
    pairs = {frozenset(p) for p in cc.checked_pairs}
    assert frozenset(("torso", "r_arm_link1")) not in pairs  # adjacent
    assert frozenset(("r_arm_link5", "l_arm_link5")) in pairs  # forearms can meet


def test_scene_edits_leave_no_stale_pairs(robot):
    home = robot.named_state("home")
    scene = Scene()
    cc = CollisionChecker(robot, scene)
    base_pairs = cc.n_pairs
    hand = robot.frame_pose(home, "r_hand")[:3, 3]
    scene.add(Obstacle("ball", "sphere", radius=0.05, pose=hand))
    assert not cc.is_valid(home)
    assert ("r_hand", "ball") in cc.colliding_pairs(home)
    scene.move("ball", hand + [0.5, 0, 0])
    assert cc.is_valid(home)
    scene.move("ball", hand)
    assert not cc.is_valid(home)
    scene.remove("ball")
    assert cc.is_valid(home) and cc.n_pairs == base_pairs
    other = Scene([Obstacle("wall", "box", size=(0.1, 2, 2), pose=[0.3, 0, 0])])
    cc.set_scene(other)
    assert cc.scene is other and cc.n_pairs > base_pairs


def test_batch_calls_agree_with_single_checks_and_count(robot):
    cc = CollisionChecker(robot, Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")))
    rng = np.random.default_rng(0)
    Q = np.array([robot.random_configuration(rng) for _ in range(60)])
    single = np.array([cc.is_valid(q) for q in Q])
    assert 0 < single.sum() < len(Q)
    cc.reset_count()
    np.testing.assert_array_equal(cc.are_valid(Q), single)
    assert cc.check_count == len(Q)
    first = int(np.argmin(single))
    cc.reset_count()
    assert cc.first_invalid(Q) == first and cc.check_count == first + 1
    assert cc.first_invalid(Q[single]) == -1


def test_clearance_and_padding(robot):
    home = robot.named_state("home")
    hand = robot.frame_pose(home, "r_hand")[:3, 3]
    scene = Scene([Obstacle("ball", "sphere", radius=0.05, pose=hand + [0.0, -0.2, 0.0])])
    cc = CollisionChecker(robot, scene)
    d = cc.clearance(home)
    assert 0 < d < 0.2
    assert cc.closest_pair(home)[1] == pytest.approx(d)
    assert not CollisionChecker(robot, scene, padding=d + 0.01).is_valid(home)
    assert CollisionChecker(robot, scene, padding=max(d - 0.01, 0)).is_valid(home)


def test_bisection_order_is_a_permutation_and_any_invalid_agrees(robot):
    for n in (0, 1, 2, 3, 10, 33):
        assert sorted(bisection_order(n).tolist()) == list(range(n))
    assert bisection_order(9)[:3].tolist() == [8, 0, 4]
    cc = CollisionChecker(robot, Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")))
    line = np.linspace(START13, GOAL13, 41)
    assert cc.any_invalid(line) and not cc.any_invalid(line[:1])
    cc.reset_count()
    cc.any_invalid(line)
    assert cc.check_count == 3  # last, first, then the (colliding) middle


@pytest.mark.parametrize("mode", ["naive", "aabb_tree"])
def test_broadphase_agrees_with_pair_loop(robot, mode):
    scene = Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml"))
    fast, loop = CollisionChecker(robot, scene, broadphase=mode), CollisionChecker(robot, scene, broadphase="none")
    rng = np.random.default_rng(5)
    Q = np.array([robot.random_configuration(rng) for _ in range(300)])
    clear = np.array([abs(loop.clearance(q)) > 1e-4 for q in Q])  # skip GJK-borderline contacts
    np.testing.assert_array_equal(fast.are_valid(Q)[clear], loop.are_valid(Q)[clear])
    # padded: the broad phase's boxes grow with the security margin, so it still agrees with the pair loop
    padded_fast = CollisionChecker(robot, scene, padding=0.01, broadphase=mode)
    padded_loop = CollisionChecker(robot, scene, padding=0.01, broadphase="none")
    clear = np.array([abs(padded_loop.clearance(q)) > 1e-4 for q in Q])
    padded = padded_loop.are_valid(Q)
    np.testing.assert_array_equal(padded_fast.are_valid(Q)[clear], padded[clear])
    assert padded_fast.broadphase == mode and (padded[clear] != loop.are_valid(Q)[clear]).any()
    with pytest.raises(ValueError, match="broadphase"):
        CollisionChecker(robot, scene, broadphase="octree")


def test_mesh_obstacle_from_yaml(robot, tmp_path):
    stl = example_robot_data_dir() / "panda_description/meshes/collision/link0.stl"
    home = robot.named_state("home")
    hand = robot.frame_pose(home, "r_hand")[:3, 3]
    path = tmp_path / "scene.yaml"
    path.write_text(
        f"obstacles:\n  - {{name: part, type: mesh, path: {stl}, scale: [1, 1, 1], "
        f"pose: {{xyz: [{hand[0]}, {hand[1]}, {hand[2] - 0.05}]}}}}\n"
    )
    scene = Scene.from_yaml(str(path))
    cc = CollisionChecker(robot, scene)
    assert ("r_hand", "part") in cc.colliding_pairs(home)
    scene.move("part", [1.5, 0, 0])
    assert cc.is_valid(home)
