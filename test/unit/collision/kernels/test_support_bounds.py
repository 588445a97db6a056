"""support_bounds: separating-axis lower bounds of the distance between convex shapes (GJK's axes)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from maru_planner.collision.checker import robot_hull
from maru_planner.collision.kernels.support_bounds import (
    BOX,
    CYLINDER,
    HULL,
    SPHERE,
    convex_bound,
    load_primitive,
    new_records,
    place_shape,
)
from maru_planner.collision.spheres import ScenePrimitives
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


def _tally(bounds: list[tuple[float, float]]) -> tuple[int, int]:
    """Every (bound, coal's distance) sound (<= the distance, <= 0 where they overlap); (placements apart, those
    whose bound is within GJK's tolerance of the distance)."""
    apart = close = 0
    for bound, distance in bounds:
        assert bound <= max(distance, 0.0) + 1e-9
        if distance > 1e-4:
            apart += 1
            close += bound >= distance - (1e-5 + 2e-3 * distance)
    return apart, close


def _bound(verts, rot, pos, obstacle, enough=np.inf):
    kinds, cs, rs, ss, vr = new_records()
    kinds[0], cs[0], rs[0], vr[0] = HULL, pos, rot, (0, len(verts))
    load_primitive(0, *ScenePrimitives.from_obstacles([obstacle]).as_tuple()[:-1], 1, kinds, cs, rs, ss)
    return convex_bound(kinds, cs, rs, ss, vr, verts, enough, rot @ verts.mean(axis=0) + pos)


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_the_bound_never_exceeds_coals_distance_and_is_tight_when_apart(panda_hulls, kind):
    """Sound on 300 random placements (overlapping ones included: then it is <= 0) and, where hull and obstacle are
    apart, within GJK's tolerance of coal's distance in nearly every case (a looser one is still a bound)."""
    rng = np.random.default_rng(sorted(KINDS).index(kind))
    pairs = [_random_pair(rng, panda_hulls, kind) for _ in range(300)]
    apart, close = _tally([(_bound(*pair[:4]), pair[4]) for pair in pairs])
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


ROBOT_SHAPES = {  # coal shape and its record (kind, size) as robot_shape_records makes them
    "box": lambda rng: (lambda half: (coal.Box(*(2 * half)), BOX, half))(rng.uniform(0.01, 0.2, 3)),
    "sphere": lambda rng: (lambda r: (coal.Sphere(r), SPHERE, np.array([r, 0.0, 0.0])))(rng.uniform(0.01, 0.2)),
    "cylinder": lambda rng: (lambda r, h: (coal.Cylinder(r, 2 * h), CYLINDER, np.array([r, 0.0, h])))(
        rng.uniform(0.01, 0.2), rng.uniform(0.01, 0.25)
    ),
}


def _placed(rng, shape_kind, slot, records, verts_start):
    """A random robot shape (coal geometry, world placement) placed into record ``slot`` by ``place_shape``: a
    joint pose times a placement in the joint's frame."""
    kinds, cs, rs, ss, vr = records
    shape, kind, size = ROBOT_SHAPES[shape_kind](rng)
    joint_rot, joint_pos = pin.exp3(rng.normal(size=3)), rng.uniform(-0.3, 0.3, 3)
    local_rot, local_pos = pin.exp3(rng.normal(size=3)), rng.uniform(-0.1, 0.1, 3)
    place_shape(0, joint_rot, joint_pos, np.array([kind]), local_rot[None], local_pos[None], size[None], verts_start,
                slot, kinds, cs, rs, ss, vr)  # fmt: skip
    return shape, coal.Transform3s(joint_rot @ local_rot, joint_rot @ local_pos + joint_pos)


@pytest.mark.parametrize("kind_a", sorted(ROBOT_SHAPES))
@pytest.mark.parametrize("kind_b", sorted(KINDS))
def test_between_primitives_the_bound_is_coals_distance(kind_a, kind_b):
    """A placed robot primitive against an obstacle's: sound on 200 random placements and, apart, within GJK's
    tolerance of coal's distance in nearly every case (this is what lets certification skip coal for them)."""
    rng = np.random.default_rng(10 * sorted(ROBOT_SHAPES).index(kind_a) + sorted(KINDS).index(kind_b))
    bounds = []
    no_verts = np.zeros(2, dtype=np.int64)
    for _ in range(200):
        records = new_records()
        shape, placement = _placed(rng, kind_a, 0, records, no_verts)
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = pin.exp3(rng.normal(size=3)), rng.uniform(-0.4, 0.4, 3)
        obstacle = Obstacle("o", kind_b, pose=pose, **KINDS[kind_b](rng))
        load_primitive(0, *ScenePrimitives.from_obstacles([obstacle]).as_tuple()[:-1], 1, *records[:4])
        distance = coal.distance(shape, placement, obstacle.geometry(), coal.Transform3s(pose[:3, :3], pose[:3, 3]),
                                 coal.DistanceRequest(), coal.DistanceResult())  # fmt: skip
        bounds.append((convex_bound(*records, np.zeros((0, 3)), np.inf, records[1][0].copy()), distance))
    apart, close = _tally(bounds)
    assert apart > 30 and close >= 0.95 * apart


def test_between_two_placed_hulls_the_bound_holds(panda_hulls):
    """Two robot hulls (a self pair of meshes): sound, and tight where apart."""
    rng = np.random.default_rng(3)
    bounds = []
    for _ in range(100):
        picks = rng.integers(len(panda_hulls), size=2)
        verts = [np.asarray(panda_hulls[i].points(), dtype=float) for i in picks]
        start = np.array([0, len(verts[0]), len(verts[0]) + len(verts[1])], dtype=np.int64)
        records = new_records()
        placements = []
        for slot in (0, 1):
            rot, pos = pin.exp3(rng.normal(size=3)), rng.uniform(-0.4, 0.4, 3)
            place_shape(slot, rot, pos, np.array([HULL, HULL]), np.stack([np.eye(3)] * 2), np.zeros((2, 3)),
                        np.zeros((2, 3)), start, slot, *records)  # fmt: skip
            placements.append(coal.Transform3s(rot, pos))
        distance = coal.distance(panda_hulls[picks[0]], placements[0], panda_hulls[picks[1]], placements[1],
                                 coal.DistanceRequest(), coal.DistanceResult())  # fmt: skip
        bounds.append((convex_bound(*records, np.concatenate(verts), np.inf, records[1][0].copy()), distance))
    apart, close = _tally(bounds)
    assert apart > 20 and close >= 0.95 * apart
