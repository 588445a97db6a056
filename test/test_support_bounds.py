"""support_bounds: separating-axis lower bounds of a robot hull's distance to an obstacle primitive (GJK's axes)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from maru_planner.collision.checker import robot_hull
from maru_planner.collision.spheres import ScenePrimitives
from maru_planner.collision.support_bounds import hull_primitive_bound
from maru_planner.robot import load_example_robot
from maru_planner.scene import Obstacle

KINDS = {
    "box": lambda rng: {"size": list(rng.uniform(0.02, 0.4, 3))},
    "sphere": lambda rng: {"radius": float(rng.uniform(0.01, 0.2))},
    "cylinder": lambda rng: {"radius": float(rng.uniform(0.01, 0.2)), "length": float(rng.uniform(0.02, 0.5))},
}


@pytest.fixture(scope="module")
def panda_hulls() -> list:
    robot = load_example_robot("panda")
    return [robot_hull(obj.geometry) for obj in robot.collision_model.geometryObjects
            if isinstance(obj.geometry, coal.BVHModelBase)]  # fmt: skip


def _random_pair(rng, hulls, kind):
    """(hull vertices, rotation, translation, obstacle, coal's distance between the hull and the obstacle)."""
    hull = hulls[int(rng.integers(len(hulls)))]
    rot, pos = pin.exp3(rng.normal(size=3)), rng.uniform(-0.3, 0.3, 3)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = pin.exp3(rng.normal(size=3)), rng.uniform(-0.4, 0.4, 3)
    obstacle = Obstacle("o", kind, pose=pose, **KINDS[kind](rng))
    distance = coal.distance(hull, coal.Transform3s(rot, pos), obstacle.geometry(),
                             coal.Transform3s(pose[:3, :3], pose[:3, 3]), coal.DistanceRequest(),
                             coal.DistanceResult())  # fmt: skip
    return np.asarray(hull.points(), dtype=float), rot, pos, obstacle, distance


def _bound(verts, rot, pos, obstacle, enough=np.inf):
    primitives = ScenePrimitives.from_obstacles([obstacle]).as_tuple()[:-1]
    near = rot @ verts.mean(axis=0) + pos
    return hull_primitive_bound(rot, pos, verts, 0, len(verts), 0, *primitives, enough, near)


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_the_bound_never_exceeds_coals_distance_and_is_tight_when_apart(panda_hulls, kind):
    """Sound on 300 random placements (overlapping ones included: then it is <= 0) and, where hull and obstacle are
    apart, within GJK's tolerance of coal's distance in nearly every case (a looser one is still a bound)."""
    rng = np.random.default_rng(sorted(KINDS).index(kind))
    apart = close = 0
    for _ in range(300):
        verts, rot, pos, obstacle, distance = _random_pair(rng, panda_hulls, kind)
        bound = _bound(verts, rot, pos, obstacle)
        assert bound <= max(distance, 0.0) + 1e-9
        if distance > 1e-4:
            apart += 1
            close += bound >= distance - (1e-5 + 2e-3 * distance)
    assert apart > 50 and close >= 0.95 * apart


def test_the_bound_stops_once_it_is_enough(panda_hulls):
    """Asked for less than the distance, the bound reaches the request (and stays a bound)."""
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(100):
        verts, rot, pos, obstacle, distance = _random_pair(rng, panda_hulls, "box")
        if distance < 0.02:
            continue
        bound = _bound(verts, rot, pos, obstacle, enough=0.5 * distance)
        assert 0.5 * distance <= bound <= distance + 1e-9
        checked += 1
    assert checked > 20


def test_a_hull_around_the_obstacle_is_not_apart(panda_hulls):
    """A small sphere inside the hull: the bound says they may touch."""
    verts = np.asarray(panda_hulls[0].points(), dtype=float)
    centre = verts.mean(axis=0)
    pose = np.eye(4)
    pose[:3, 3] = centre
    assert _bound(verts, np.eye(3), np.zeros(3), Obstacle("o", "sphere", pose=pose, radius=0.001)) <= 0.0
