"""Sphere collision checker: FK, sphere coverage, agreement with the exact pinocchio/coal checker."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from maru_planner.collision import CollisionChecker
from maru_planner.collision.kernels.fk import frame_placements_nb, joint_poses_nb
from maru_planner.collision.kinematic_tree import KinematicTree, batch_joint_poses
from maru_planner.collision.sphere_model import SphereFitOptions, subdivide, surface_of
from maru_planner.collision.spheres import SphereCollisionChecker, densify, verify_path
from maru_planner.scene import Obstacle, Scene


def random_scene(rng: np.random.Generator, n: int = 6, center=(0.0, 0.0, 0.45), spread=(0.6, 0.6, 0.45)) -> Scene:
    """Boxes, spheres and cylinders with random poses around the robot."""
    obstacles = []
    for i in range(n):
        pose = np.eye(4)
        pose[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))
        pose[:3, 3] = np.asarray(center) + rng.uniform(-1, 1, 3) * np.asarray(spread)
        kind = ("box", "sphere", "cylinder")[i % 3]
        if kind == "box":
            obstacles.append(Obstacle(f"o{i}", "box", size=tuple(rng.uniform(0.05, 0.3, 3)), pose=pose))
        elif kind == "sphere":
            obstacles.append(Obstacle(f"o{i}", "sphere", radius=rng.uniform(0.03, 0.12), pose=pose))
        else:
            obstacles.append(
                Obstacle(f"o{i}", "cylinder", radius=rng.uniform(0.03, 0.1), length=rng.uniform(0.1, 0.4), pose=pose)
            )
    return Scene(obstacles)


def random_configs(robot, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([robot.random_configuration(rng) for _ in range(n)])


@pytest.mark.parametrize("robot_name", ["panda", "maru1"])
def test_batch_fk_matches_pinocchio(robot_name, request):
    robot = request.getfixturevalue(robot_name)
    tree = KinematicTree.from_pinocchio(robot.model)
    Q = random_configs(robot, 20, 0)
    rot, pos = batch_joint_poses(tree, Q)
    r1 = np.empty((tree.njoints, 3, 3))
    p1 = np.empty((tree.njoints, 3))
    data = robot.model.createData()
    for i, q in enumerate(Q):
        pin.forwardKinematics(robot.model, data, q)
        joint_poses_nb(q, tree.parent, tree.kind, tree.axis, tree.placement_rot, tree.placement_pos, tree.idx_q, r1, p1)
        for j in range(tree.njoints):
            np.testing.assert_allclose(rot[i, j], data.oMi[j].rotation, atol=1e-12)
            np.testing.assert_allclose(pos[i, j], data.oMi[j].translation, atol=1e-12)
            np.testing.assert_allclose(r1[j], data.oMi[j].rotation, atol=1e-12)
            np.testing.assert_allclose(p1[j], data.oMi[j].translation, atol=1e-12)


@pytest.mark.parametrize("robot_name", ["panda", "maru1"])
def test_frame_placements_match_pinocchios_geometry_placements(robot_name, request):
    """The placements the sphere checker hands coal for its exact checks are Pinocchio's own."""
    robot = request.getfixturevalue(robot_name)
    tree = KinematicTree.from_pinocchio(robot.model)
    geoms = robot.collision_model.geometryObjects
    joint = np.array([obj.parentJoint for obj in geoms], dtype=np.int64)
    local_rot = np.array([obj.placement.rotation for obj in geoms])
    local_pos = np.array([obj.placement.translation for obj in geoms])
    rot, pos = np.empty((tree.njoints, 3, 3)), np.empty((tree.njoints, 3))
    out_rot, out_pos = np.empty((len(geoms), 3, 3)), np.empty((len(geoms), 3))
    data, gdata = robot.model.createData(), pin.GeometryData(robot.collision_model)
    for q in random_configs(robot, 10, 1):
        joint_poses_nb(q, tree.parent, tree.kind, tree.axis, tree.placement_rot, tree.placement_pos, tree.idx_q, rot,
                       pos)  # fmt: skip
        frame_placements_nb(rot, pos, joint, local_rot, local_pos, out_rot, out_pos)
        pin.updateGeometryPlacements(robot.model, data, robot.collision_model, gdata, q)
        for g in range(len(geoms)):
            np.testing.assert_allclose(out_rot[g], gdata.oMg[g].rotation, atol=1e-12)
            np.testing.assert_allclose(out_pos[g], gdata.oMg[g].translation, atol=1e-12)


def test_unsupported_joint_is_named():
    model = pin.Model()
    model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    with pytest.raises(ValueError, match="ball"):
        KinematicTree.from_pinocchio(model)


@pytest.mark.parametrize("robot_name", ["panda", "maru1"])
def test_spheres_cover_every_surface_point_and_inner_balls_lie_inside(robot_name, request):
    robot = request.getfixturevalue(robot_name)
    checker = SphereCollisionChecker(robot)
    sm = checker.spheres
    options = SphereFitOptions()
    rng = np.random.default_rng(1)
    for g, obj in enumerate(robot.collision_model.geometryObjects):
        sl = slice(sm.group_start[g], sm.group_start[g + 1])
        centers, radii, inner = sm.center[sl], sm.radius[sl], sm.inner[sl]
        vertices, points = _surface_points(obj.geometry, options, rng)
        points = points @ obj.placement.rotation.T + obj.placement.translation
        gap = np.linalg.norm(points[:, None] - centers[None], axis=2) - radii
        assert gap.min(axis=1).max() <= 1e-9, f"{obj.name}: a surface point lies outside every sphere"
        assert np.all(inner <= radii + 1e-12) and np.all(inner >= 0.0)
        # a point on each inner ball must not be outside the (convex) geometry, in the geometry's own frame
        c_local = (centers - obj.placement.translation) @ obj.placement.rotation
        direction = rng.normal(size=(len(c_local), 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        probe = c_local + 0.999 * inner[:, None] * direction
        assert _inside(obj.geometry, vertices, probe).all(), f"{obj.name}: an inner ball leaves the geometry"


def _surface_points(geometry, options, rng):
    """(vertices, random points on the surface) of a geometry in its own frame."""
    import coal

    if isinstance(geometry, coal.Sphere):
        d = rng.normal(size=(200, 3))
        points = geometry.radius * d / np.linalg.norm(d, axis=1, keepdims=True)
        return points, points
    vertices, triangles = surface_of(geometry, options)
    if isinstance(geometry, coal.Cylinder):  # the true surface, not the circumscribed prism
        angle, z = rng.uniform(0, 2 * np.pi, 400), rng.uniform(-geometry.halfLength, geometry.halfLength, 400)
        rim = np.c_[geometry.radius * np.cos(angle), geometry.radius * np.sin(angle), z]
        cap = np.c_[rim[:, :2] * np.sqrt(rng.uniform(0, 1, (400, 1))), np.sign(z) * geometry.halfLength]
        return vertices, np.concatenate([rim, cap])
    corners = subdivide(vertices, triangles, 0.05)
    w = rng.dirichlet(np.ones(3), size=len(corners))
    return vertices, np.concatenate([np.einsum("tk,tka->ta", w, corners), vertices])


def _inside(geometry, vertices, points):
    import coal
    from scipy.spatial import Delaunay

    if isinstance(geometry, coal.Box):
        return (np.abs(points) <= np.asarray(geometry.halfSide) + 1e-9).all(axis=1)
    if isinstance(geometry, coal.Cylinder):
        return (np.linalg.norm(points[:, :2], axis=1) <= geometry.radius + 1e-9) & (
            np.abs(points[:, 2]) <= geometry.halfLength + 1e-9
        )
    if isinstance(geometry, coal.Sphere):
        return np.linalg.norm(points, axis=1) <= geometry.radius + 1e-9
    return Delaunay(vertices).find_simplex(points, tol=1e-9) >= 0


@pytest.mark.parametrize("robot_name", ["panda", "maru1"])
def test_agreement_with_exact_checker(robot_name, request):
    """confirm=True answers exactly like the exact checker; confirm=False never says valid wrongly."""
    robot = request.getfixturevalue(robot_name)
    center = (0.0, 0.0, 0.45) if robot_name == "panda" else (0.3, 0.0, 0.3)
    scene = random_scene(np.random.default_rng(3), center=center)
    exact = CollisionChecker(robot, scene)
    fast = SphereCollisionChecker(robot, scene)
    spheres_only = SphereCollisionChecker(robot, scene, confirm=False)
    Q = random_configs(robot, 600, 4)
    truth = exact.are_valid(Q)
    assert 0.1 < truth.mean() < 0.95, "the scene should make some but not all states collide"
    np.testing.assert_array_equal(fast.are_valid(Q), truth)
    conservative = spheres_only.are_valid(Q)
    assert not np.any(conservative & ~truth), "the pure sphere model called a colliding state valid"
    assert (conservative == truth).mean() > 0.8
    for q in Q[:60]:
        assert set(fast.colliding_pairs(q)) == set(exact.colliding_pairs(q))
        exact_clearance = exact.clearance(q)
        if exact_clearance > 0.0:  # spheres contain the links: a lower bound of a positive clearance
            assert fast.clearance(q) <= exact_clearance + 1e-6
        else:
            assert fast.clearance(q) < 0.0


def test_numpy_path_matches_numba(panda):
    scene = random_scene(np.random.default_rng(5))
    fast = SphereCollisionChecker(panda, scene)
    slow = SphereCollisionChecker(panda, scene, use_numba=False)
    Q = random_configs(panda, 60, 6)
    np.testing.assert_array_equal(fast.are_valid(Q), slow.are_valid(Q))
    for q in Q[:10]:
        assert fast.colliding_pairs(q) == slow.colliding_pairs(q)
        assert fast.clearance(q) == pytest.approx(slow.clearance(q), abs=1e-9)
    slow_spheres = SphereCollisionChecker(panda, scene, use_numba=False, confirm=False)
    fast_spheres = SphereCollisionChecker(panda, scene, confirm=False)
    np.testing.assert_array_equal(fast_spheres.are_valid(Q), slow_spheres.are_valid(Q))


def test_first_invalid_stops_at_first_hit_and_counts(panda):
    scene = random_scene(np.random.default_rng(7))
    exact = CollisionChecker(panda, scene)
    fast = SphereCollisionChecker(panda, scene)
    Q = random_configs(panda, 200, 8)
    valid = exact.are_valid(Q)
    free, hit = Q[valid][:5], Q[~valid][:1]
    batch = np.vstack([free, hit, free])
    fast.reset_count()
    assert fast.first_invalid(batch) == 5
    assert fast.check_count == 6
    assert fast.first_invalid(free) == -1
    assert fast.check_count == 11
    assert fast.is_valid(free[0]) and not fast.is_valid(hit[0])
    assert fast.are_valid(batch).tolist() == [True] * 5 + [False] + [True] * 5


def test_scene_edits_are_picked_up(panda):
    scene = Scene()
    fast = SphereCollisionChecker(panda, scene)
    q = panda.neutral()
    assert fast.is_valid(q)
    hand = panda.frame_pose(q, "panda_hand")[:3, 3]
    scene.add(Obstacle("ball", "sphere", radius=0.05, pose=tuple(hand)))
    assert not fast.is_valid(q)
    assert ("panda_hand", "ball") in fast.colliding_pairs(q)
    scene.remove("ball")
    assert fast.is_valid(q)


def test_wrong_configuration_size_is_rejected(panda):
    fast = SphereCollisionChecker(panda)
    with pytest.raises(ValueError, match="nq"):
        fast.is_valid(np.zeros(panda.nq + 1))


def test_verify_path_finds_the_failing_segment(panda):
    q0 = panda.named_state("default")  # arm bent forward: turning joint 1 sweeps the hand sideways
    q1 = q0.copy()
    q1[0] += 1.0
    hand = panda.frame_pose(0.5 * (q0 + q1), "panda_hand")[:3, 3]
    scene = Scene([Obstacle("ball", "sphere", radius=0.04, pose=tuple(hand))])
    exact = CollisionChecker(panda, scene)
    q_around = q0.copy()
    q_around[0] -= 1.0
    ok = verify_path(exact, np.array([q0, q_around]), resolution=0.02)
    assert ok.valid and ok.first_invalid_segment == -1
    bad = verify_path(exact, np.array([q_around, q0, q1]), resolution=0.02)
    assert not bad.valid and bad.first_invalid_segment == 1
    states, segment = densify(np.array([q0, q1]), 0.1)
    assert len(states) == 11 and np.all(np.abs(np.diff(states, axis=0)).max(axis=1) <= 0.1 + 1e-12)
    assert segment.tolist() == [0] * 11
    with pytest.raises(ValueError):
        verify_path(exact, np.array([q0, q1]), resolution=0.0)


def test_a_first_fit_is_announced_until_the_model_is_on_disk(panda, tmp_path, monkeypatch):
    from maru_planner.collision import sphere_model

    monkeypatch.setenv("MARU_PLANNER_CACHE", str(tmp_path))
    notice = sphere_model.first_fit_notice("panda", panda.collision_model)
    assert notice is not None and "fitting the sphere model of panda" in notice and str(tmp_path) in notice
    path = sphere_model.cached_path(panda.collision_model)
    assert path.parent == tmp_path / "spheres"
    path.parent.mkdir(parents=True)
    path.write_bytes(b"")  # where load_or_fit keeps it
    assert sphere_model.first_fit_notice("panda", panda.collision_model) is None
