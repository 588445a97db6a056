"""SphereCover: balls that provably contain each robot geometry (the certifier's cheap distance bound)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from maru_planner.collision.certify.cover import (
    DISTANCE_TOLERANCE,
    SphereCover,
    cover_bounds_nb,
    solid_balls,
    solid_inside_spheres,
)
from maru_planner.collision.certify.pairs import kernel_primitives
from maru_planner.collision.kinematic_tree import KinematicTree, batch_joint_poses
from maru_planner.collision.sphere_model import load_or_fit
from maru_planner.robot import RobotModel, load_example_robot
from maru_planner.scene import Obstacle


def sphere_model(robot: RobotModel):
    return load_or_fit(robot.model, robot.collision_model)


def test_the_sphere_cover_contains_every_mesh_triangle():
    """The premise of the cover bound: each triangle of a mesh geometry lies inside one sphere of its group
    (its vertices and centroid are inside the union of the group's spheres)."""
    robot = load_example_robot("panda")
    spheres = sphere_model(robot)
    meshes = 0
    for g, obj in enumerate(robot.collision_model.geometryObjects):
        if not hasattr(obj.geometry, "vertices"):
            continue
        meshes += 1
        vertices = np.asarray(obj.geometry.vertices(), dtype=float)
        triangles = np.array([[t[i] for i in range(3)] for t in (obj.geometry.tri_indices(k)
                              for k in range(obj.geometry.num_tris))])  # fmt: skip
        points = np.concatenate([vertices, vertices[triangles].mean(axis=1)]) @ obj.placement.rotation.T
        points += obj.placement.translation  # in the parent joint's frame, like the spheres
        mine = slice(spheres.group_start[g], spheres.group_start[g + 1])
        gaps = np.linalg.norm(points[:, None] - spheres.center[mine][None], axis=2) - spheres.radius[mine]
        assert gaps.min(axis=1).max() <= 1e-9, obj.name
    assert meshes >= 9


def test_without_its_sphere_model_only_primitives_are_covered():
    panda, maru = load_example_robot("panda"), RobotModel.maru1()
    meshes = np.array([isinstance(obj.geometry, coal.BVHModelBase) for obj in panda.collision_model.geometryObjects])
    for model in (None, sphere_model(maru)):  # none, or another robot's: the fingers' boxes get solid_balls
        cover = SphereCover.of(panda, model)
        assert cover is not None and np.array_equal(cover.covered, ~meshes)
    assert SphereCover.of(panda, sphere_model(panda)).covered.all()
    assert SphereCover.of(maru, None).covered.all()  # Maru-1: boxes, cylinders and spheres only


def _points_inside(geometry, placement: pin.SE3, rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` random points of a box, cylinder or sphere, in the frame ``placement`` places it in."""
    if isinstance(geometry, coal.Box):
        local = rng.uniform(-1.0, 1.0, (n, 3)) * np.asarray(geometry.halfSide)
    else:
        radius = geometry.radius
        local = rng.uniform(-radius, radius, (4 * n, 3))
        if isinstance(geometry, coal.Cylinder):
            local[:, 2] = rng.uniform(-geometry.halfLength, geometry.halfLength, len(local))
            local = local[np.hypot(local[:, 0], local[:, 1]) <= radius][:n]
        else:
            local = local[np.linalg.norm(local, axis=1) <= radius][:n]
    return local @ placement.rotation.T + placement.translation


def test_a_solid_proven_inside_the_balls_has_every_sampled_point_in_one():
    """Soundness on random solids and balls: a proof is never wrong (2,000 sampled points of each proven solid)."""
    rng = np.random.default_rng(7)
    proven = 0
    for i in range(150):
        geometry = [coal.Box(*rng.uniform(0.02, 0.2, 3)), coal.Cylinder(rng.uniform(0.02, 0.1), rng.uniform(0.02, 0.2)),
                    coal.Sphere(rng.uniform(0.02, 0.1))][i % 3]  # fmt: skip
        placement = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.02)
        k = int(rng.integers(1, 12))
        centers, radii = rng.normal(size=(k, 3)) * 0.05, rng.uniform(0.05, 0.25, k)
        if solid_inside_spheres(geometry, placement, centers, radii):
            proven += 1
            points = _points_inside(geometry, placement, rng, 2000)
            inside = (np.linalg.norm(points[:, None] - centers, axis=2) <= radii + 1e-9).any(axis=1)
            assert inside.all(), (i, geometry, k)
    assert 20 < proven < 150  # both answers occur


def test_the_cover_of_a_robot_is_proven_once_and_remembered(monkeypatch):
    from maru_planner.collision.certify import cover

    maru = RobotModel.maru1()
    spheres = sphere_model(maru)
    monkeypatch.setattr(cover, "SOLID_COVERS", {})
    first = SphereCover.of(maru, spheres)
    calls = []
    monkeypatch.setattr(cover, "solid_inside_spheres", lambda *args: calls.append(args) or True)
    again = SphereCover.of(maru, spheres)
    assert not calls and np.array_equal(first.covered, again.covered)
    assert all(np.array_equal(a, b) for a, b in zip(first.arrays, again.arrays, strict=True))


def test_a_solid_counts_as_covered_only_when_its_whole_volume_is_in_the_balls():
    box, here = coal.Box(0.2, 0.1, 0.1), pin.SE3.Identity()
    assert solid_inside_spheres(box, here, np.zeros((1, 3)), [np.linalg.norm([0.1, 0.05, 0.05])])
    corners = np.array([[x, y, z] for x in (-0.1, 0.1) for y in (-0.05, 0.05) for z in (-0.05, 0.05)])
    assert not solid_inside_spheres(box, here, corners, np.full(8, 0.06))  # the surface's corners, not its middle
    two = np.array([[-0.05, 0.0, 0.0], [0.05, 0.0, 0.0]])
    assert solid_inside_spheres(box, here, two, np.full(2, 0.1))  # two balls, each holding one half
    assert not solid_inside_spheres(box, here, two, np.full(2, 0.085))  # each half's far corners stick out
    moved = pin.SE3(np.eye(3), np.array([1.0, 0.0, 0.0]))
    assert solid_inside_spheres(box, moved, two + [1.0, 0.0, 0.0], np.full(2, 0.1))
    assert not solid_inside_spheres(box, moved, two, np.full(2, 0.1))
    cylinder = coal.Cylinder(0.05, 0.2)  # radius, length: its bounding box's corners are off the disc
    assert solid_inside_spheres(cylinder, here, np.zeros((1, 3)), [0.12])  # hypot(0.05, 0.1) = 0.112: cells need slack
    assert not solid_inside_spheres(cylinder, here, np.zeros((1, 3)), [0.1])
    assert solid_inside_spheres(coal.Sphere(0.1), here, np.array([[0.01, 0.0, 0.0]]), [0.11])
    assert not solid_inside_spheres(coal.Sphere(0.1), here, np.array([[0.02, 0.0, 0.0]]), [0.11])


@pytest.mark.parametrize("shape", [coal.Box(0.3, 0.04, 0.1), coal.Box(0.05, 0.05, 0.05), coal.Cylinder(0.04, 0.3),
                                   coal.Cylinder(0.1, 0.02)])  # fmt: skip
def test_solid_balls_contain_their_solid(shape):
    centers, radii = solid_balls(shape)
    rng = np.random.default_rng(2)
    if isinstance(shape, coal.Box):
        points = rng.uniform(-1.0, 1.0, (20000, 3)) * shape.halfSide
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * shape.halfSide
        points = np.concatenate([points, corners])
    else:
        angle, radial = rng.uniform(0.0, 2 * np.pi, 20000), shape.radius * np.sqrt(rng.uniform(0.0, 1.0, 20000))
        radial[:2000] = shape.radius  # the rim and the caps' edges
        z = rng.uniform(-1.0, 1.0, 20000) * shape.halfLength
        z[:200] = np.sign(z[:200]) * shape.halfLength
        points = np.c_[radial * np.cos(angle), radial * np.sin(angle), z]
    outside = np.linalg.norm(points[:, None] - centers[None], axis=2) - radii
    assert outside.min(axis=1).max() <= 1e-12
    assert solid_balls(coal.Capsule(0.1, 0.2)) is None
    centers, radii = solid_balls(coal.Sphere(0.1))
    assert np.allclose(centers, 0.0) and np.allclose(radii, 0.1)


def test_cover_bounds_are_the_balls_least_distance_below_enough_and_at_least_enough_above():
    """:func:`cover_bounds_nb` skips clusters whose bound reaches the row's ``enough``: its bound is the exact least
    ball distance where that is below ``enough``, else between ``enough`` and it (never above the balls' distance)."""
    robot = load_example_robot("panda")
    cover = SphereCover.of(robot, sphere_model(robot))
    s_joint, s_center, s_radius, c_start, _, _, _, g_clusters = cover.arrays
    obstacles = [Obstacle("box", "box", size=(0.3, 0.2, 0.4), pose=[0.45, 0.1, 0.4]),
                 Obstacle("ball", "sphere", radius=0.08, pose=[0.3, -0.3, 0.6])]  # fmt: skip
    primitives, _ = kernel_primitives(obstacles)
    rng = np.random.default_rng(3)
    configs = rng.uniform(robot.lower_limits, robot.upper_limits, (40, robot.nq))
    rots, poss = batch_joint_poses(KinematicTree.from_pinocchio(robot.model), configs)
    n_geoms = len(g_clusters) - 1
    rows = [(c, g, k, True) for c in range(len(configs)) for g in range(n_geoms) for k in range(2)]
    rows += [(c, g, h, False) for c in range(len(configs)) for g, h in ((1, 7), (2, 8), (3, 9))]
    config_of, first, second, obstacle = (np.array([row[i] for row in rows]) for i in range(4))
    world = np.einsum("csab,sb->csa", rots[:, s_joint], s_center) + poss[:, s_joint]  # (configs, balls, 3)
    own = [np.arange(c_start[g_clusters[g]], c_start[g_clusters[g + 1]]) for g in range(n_geoms)]
    exact = np.empty(len(rows))
    for r, (c, g, h, is_obstacle) in enumerate(rows):
        if is_obstacle:
            ob = obstacles[h]
            local = (world[c, own[g]] - ob.pose[:3, 3]) @ ob.pose[:3, :3]
            if h == 0:  # the box
                outside = np.abs(local) - 0.5 * np.asarray(ob.size)
                inside = np.minimum(outside.max(axis=1), 0.0)
                distance = np.linalg.norm(np.maximum(outside, 0.0), axis=1) + inside
            else:
                distance = np.linalg.norm(local, axis=1) - 0.08
            exact[r] = (distance - s_radius[own[g]]).min()
        else:
            gaps = np.linalg.norm(world[c, own[g]][:, None] - world[c, own[h]][None], axis=2)
            exact[r] = (gaps - s_radius[own[g]][:, None] - s_radius[own[h]][None]).min()
    exact -= DISTANCE_TOLERANCE
    enough = exact + rng.choice([-0.05, -0.01, 0.01, 0.05, np.inf], len(rows))
    bound = np.full(len(rows), -np.inf)
    cover_bounds_nb(rots, poss, np.arange(len(rows)), config_of, first, second, obstacle.astype(bool), enough,
                    *cover.arrays, *primitives, bound)  # fmt: skip
    below = exact < enough
    assert below.any() and (~below).any()
    np.testing.assert_allclose(bound[below], exact[below], atol=1e-12)
    assert np.all(bound[~below] <= exact[~below] + 1e-12)
    assert np.all(bound[~below] >= enough[~below] - DISTANCE_TOLERANCE - 1e-12)
