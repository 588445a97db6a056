"""Large scenes: far obstacles are dropped, near ones go in a tree (exact) or a grid (spheres), with the same
answers as checking every pair; scene size and build time are bounded with one-line errors."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from maru_planner.collision import CollisionChecker, SphereCollisionChecker
from maru_planner.collision.broadphase import robot_reach
from maru_planner.errors import InvalidScene
from maru_planner.robot import RobotModel, load_example_robot
from maru_planner.scene import Obstacle, Scene

EVERY_PAIR = 10**9  # pair_list_limit / grid_min_obstacles that turn the broad phases off


@pytest.fixture(scope="module")
def maru1():
    return RobotModel.maru1()


@pytest.fixture(scope="module")
def panda():
    return load_example_robot("panda")


def clutter(rng: np.random.Generator, n: int, center, spread: float, size=(0.02, 0.08)) -> list[Obstacle]:
    """Small boxes, spheres and cylinders, randomly posed around ``center``."""
    obstacles = []
    for i in range(n):
        pose = np.eye(4)
        pose[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))
        pose[:3, 3] = np.asarray(center) + rng.uniform(-spread, spread, 3)
        a, b = rng.uniform(*size, 2)
        if i % 3 == 0:
            obstacles.append(Obstacle(f"c{i}", "box", size=(a, b, a), pose=pose))
        elif i % 3 == 1:
            obstacles.append(Obstacle(f"c{i}", "sphere", radius=a / 2, pose=pose))
        else:
            obstacles.append(Obstacle(f"c{i}", "cylinder", radius=a / 2, length=b, pose=pose))
    return obstacles


def clear_of_rest_posture(robot, obstacles: list[Obstacle]) -> list[Obstacle]:
    """The obstacles not touching the robot at neutral (one inside the torso would block every configuration)."""
    touching = {name for pair in CollisionChecker(robot, Scene(obstacles)).colliding_pairs(robot.neutral())
                for name in pair}  # fmt: skip
    return [o for o in obstacles if o.name not in touching]


def far_field(rng: np.random.Generator, n: int, reach: float) -> list[Obstacle]:
    """Boxes between 2 and 20 reaches from the robot, in every direction."""
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    centres = direction * rng.uniform(2 * reach, 20 * reach, (n, 1))
    return [Obstacle(f"far{i}", "box", size=(0.3, 0.3, 0.3), pose=c) for i, c in enumerate(centres)]


def configs(robot, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([robot.random_configuration(rng) for _ in range(n)])


def self_free_configs(robot, n: int, seed: int) -> np.ndarray:
    """Configurations without self-collision: the scene decides their validity."""
    Q = configs(robot, 8 * n, seed)
    return Q[CollisionChecker(robot).are_valid(Q)][:n]


@pytest.mark.parametrize("robot_name", ["maru1", "panda"])
def test_reach_contains_every_moving_geometry(robot_name, request):
    robot = request.getfixturevalue(robot_name)
    reach = robot_reach(robot)
    data, geom = robot.model.createData(), robot.collision_model
    geom_data = pin.GeometryData(geom)
    for q in configs(robot, 200, 1):
        pin.updateGeometryPlacements(robot.model, data, geom, geom_data, q)
        for k, obj in enumerate(geom.geometryObjects):
            if obj.parentJoint == 0:
                continue
            obj.geometry.computeLocalAABB()
            box = obj.geometry.aabb_local
            corners = np.array([[x, y, z] for x in (box.min_[0], box.max_[0]) for y in (box.min_[1], box.max_[1])
                                for z in (box.min_[2], box.max_[2])])  # fmt: skip
            world = corners @ geom_data.oMg[k].rotation.T + geom_data.oMg[k].translation
            assert np.linalg.norm(world, axis=1).max() <= reach


def test_far_obstacles_cost_no_pairs_and_change_no_answer(maru1):
    rng = np.random.default_rng(2)
    near = clutter(rng, 6, (0.4, 0.0, 0.0), 0.4, size=(0.05, 0.2))
    scene = Scene(near + far_field(rng, 3000, robot_reach(maru1)))
    small, large = CollisionChecker(maru1, Scene(near)), CollisionChecker(maru1, scene)
    assert large.n_pairs == small.n_pairs and large.scene_tree is None
    Q = configs(maru1, 300, 3)
    np.testing.assert_array_equal(large.are_valid(Q), small.are_valid(Q))
    fast = SphereCollisionChecker(maru1, scene)
    assert len(fast.primitives.names) == len(near) and not fast.uses_grid
    np.testing.assert_array_equal(fast.are_valid(Q), SphereCollisionChecker(maru1, Scene(near)).are_valid(Q))


def test_far_obstacles_are_culled_once_per_scene_version(maru1, monkeypatch):
    rng = np.random.default_rng(3)
    near = clutter(rng, 4, (0.4, 0.0, 0.0), 0.3)
    scene = Scene(near + far_field(rng, 200, robot_reach(maru1)))
    calls = []
    primitive = Obstacle.kernel_primitive
    monkeypatch.setattr(Obstacle, "kernel_primitive", lambda self: calls.append(self.name) or primitive(self))
    exact = CollisionChecker(maru1, scene)
    padded = CollisionChecker(maru1, scene, padding=0.02)
    spheres = SphereCollisionChecker(maru1, scene)
    assert sum(name.startswith("far") for name in calls) == 200  # one pass, shared by the three checkers
    assert len(exact.checked_pairs) == len(padded.checked_pairs) and len(spheres.primitives.names) == len(near)
    scene.move("far0", [0.4, 0.0, 0.0])  # a new version: culled again, the moved box now within reach
    calls.clear()
    spheres.is_valid(maru1.neutral())  # picks the edit up
    assert "far0" in spheres.primitives.names
    assert sum(name.startswith("far") for name in calls) == 201  # the culling pass, then far0's conversion


@pytest.mark.parametrize("padding", [0.0, 0.02])
def test_tree_agrees_with_every_pair(maru1, padding):
    rng = np.random.default_rng(4)
    scene = Scene(clutter(rng, 150, (0.3, 0.0, 0.0), 0.8))
    tree = CollisionChecker(maru1, scene, padding=padding, pair_list_limit=0)
    pairs = CollisionChecker(maru1, scene, padding=padding, pair_list_limit=EVERY_PAIR)
    assert tree.scene_tree is not None and pairs.scene_tree is None and tree.n_pairs == pairs.n_pairs
    assert len(tree.geometry_model.collisionPairs) == len(pairs.geometry_model.collisionPairs) == pairs.n_pairs
    Q = self_free_configs(maru1, 300, 5)
    clear = np.array([abs(pairs.clearance(q)) > 1e-4 for q in Q])  # skip GJK-borderline contacts
    valid = pairs.are_valid(Q)
    assert 0 < valid.sum() < len(Q)
    np.testing.assert_array_equal(tree.are_valid(Q)[clear], valid[clear])
    for q in Q[:40]:
        assert set(tree.colliding_pairs(q)) == set(pairs.colliding_pairs(q))
        assert tree.clearance(q) == pytest.approx(pairs.clearance(q), abs=1e-6)


@pytest.mark.parametrize("robot_name", ["maru1", "panda"])
def test_grid_agrees_with_every_obstacle(robot_name, request):
    robot = request.getfixturevalue(robot_name)
    rng = np.random.default_rng(6)
    centre = (0.3, 0.0, 0.0) if robot_name == "maru1" else (0.3, 0.0, 0.5)
    wall = Obstacle("wall", "box", size=(0.02, 4.0, 4.0), pose=[0.9 * robot_reach(robot), 0.0, 0.0])  # many cells
    scene = Scene([*clear_of_rest_posture(robot, clutter(rng, 150, centre, 0.8)), wall])
    grid = SphereCollisionChecker(robot, scene)
    every = SphereCollisionChecker(robot, scene, grid_min_obstacles=EVERY_PAIR)
    reference = SphereCollisionChecker(robot, scene, use_numba=False)
    assert grid.uses_grid and not every.uses_grid
    Q = self_free_configs(robot, 400, 7)
    expected = every.are_valid(Q)
    assert 0 < expected.sum() < len(Q)
    np.testing.assert_array_equal(grid.are_valid(Q), expected)
    np.testing.assert_array_equal(reference.are_valid(Q[:60]), expected[:60])
    assert [grid.first_invalid(Q[k : k + 10]) for k in range(0, 400, 10)] == [
        every.first_invalid(Q[k : k + 10]) for k in range(0, 400, 10)
    ]


def test_scene_size_limit_names_the_obstacle():
    scene = Scene(max_obstacles=2)
    scene.add(Obstacle("a", "sphere", radius=0.1))
    scene.add(Obstacle("b", "sphere", radius=0.1))
    scene.add(Obstacle("b", "sphere", radius=0.2))  # replacing keeps the count
    with pytest.raises(InvalidScene, match="'c'.*full.*2"):
        scene.add(Obstacle("c", "sphere", radius=0.1))
    entries = [{"name": f"s{i}", "type": "sphere", "radius": 0.1} for i in range(3)]
    with pytest.raises(InvalidScene, match="3 obstacles.*limit of 2"):
        Scene.from_dict({"obstacles": entries}, max_obstacles=2)


def test_build_budget_stops_a_slow_build_with_one_line(maru1):
    rng = np.random.default_rng(8)
    scene = Scene(clutter(rng, 2100, (0.3, 0.0, 0.0), 0.6))
    for make in (CollisionChecker, SphereCollisionChecker):
        with pytest.raises(InvalidScene, match=r"budget.*of 2100 obstacles") as err:
            make(maru1, scene, build_budget=0.0)
        assert "\n" not in str(err.value)
    with pytest.raises(InvalidScene, match=r"budget.*reading obstacles.*of 2100"):
        Scene.from_dict(scene.to_dict(), budget=0.0)
