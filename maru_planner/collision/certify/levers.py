"""How far a robot's geometries can move per unit motion of each joint: the certification's rate bounds.

On ``q(t) = q0 + t (q1 - q0)`` a pair's distance changes by at most ``sum_j c_j |q1_j - q0_j|`` over the joints that
move one body of the pair but not the other, ``c_j`` the largest distance from joint ``j``'s axis to any point of the
body (revolute: :func:`joint_levers`) or 1 (prismatic).
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin

from maru_planner import errors
from maru_planner.robot.model import RobotModel

REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


def bounding_sphere(geometry: coal.CollisionGeometry) -> tuple[np.ndarray, float]:
    """Centre (in the geometry's frame) and radius of a sphere containing ``geometry``."""
    if isinstance(geometry, coal.BVHModelBase):
        vertices = np.asarray(geometry.vertices(), dtype=float)
        center = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        return center, float(np.linalg.norm(vertices - center, axis=1).max())
    if isinstance(geometry, coal.Sphere):
        return np.zeros(3), float(geometry.radius)
    if isinstance(geometry, (coal.Cylinder, coal.Cone)):
        return np.zeros(3), float(math.hypot(geometry.radius, geometry.halfLength))
    geometry.computeLocalAABB()
    return np.asarray(geometry.aabb_center, dtype=float).copy(), float(geometry.aabb_radius)


def joint_levers(robot: RobotModel) -> np.ndarray:
    """(robot geometries, nq): the most any point of a geometry moves per unit motion of each joint.

    Revolute joint upstream of the geometry: its joint offsets down to the geometry's joint (plus
    the travel of prismatic joints in between, from the joint limits) plus the geometry's reach from
    its own joint origin -- a bound on the distance from the axis valid in every configuration.
    Prismatic: 1. Joints not upstream: 0.
    """
    model = robot.model
    offset = np.zeros(model.njoints)  # longest possible distance from a joint's origin to its parent's
    prismatic = np.zeros(model.njoints, dtype=bool)
    for j in range(1, model.njoints):
        kind, name, i = model.joints[j].shortname(), model.names[j], model.joints[j].idx_q
        if kind not in REVOLUTE + PRISMATIC:
            raise errors.InvalidRequest(f"joint {name!r} ({kind}): only revolute and prismatic joints are certified")
        offset[j] = np.linalg.norm(model.jointPlacements[j].translation)
        if kind in PRISMATIC:
            travel = max(abs(robot.lower_limits[i]), abs(robot.upper_limits[i]))
            if not math.isfinite(travel):
                raise errors.InvalidRequest(f"prismatic joint {name!r} needs finite limits to be certified")
            offset[j] += travel
            prismatic[j] = True
    geometries = robot.collision_model.geometryObjects
    levers = np.zeros((len(geometries), model.nq))
    for g, obj in enumerate(geometries):
        center, radius = bounding_sphere(obj.geometry)
        reach = float(np.linalg.norm(obj.placement.act(center))) + radius
        j = obj.parentJoint
        while j != 0:
            levers[g, model.joints[j].idx_q] = 1.0 if prismatic[j] else reach
            reach += offset[j]
            j = model.parents[j]
    return levers


def joint_of_q(model: pin.Model, i: int) -> int:
    return next(j for j in range(1, model.njoints) if model.joints[j].idx_q == i)


def downstream_levers(robot: RobotModel, levers: np.ndarray) -> np.ndarray:
    """(geometries, nq, nq): ``[g, j, k]`` = lever of joint k on g if k is below joint j on g's chain, else 0."""
    model = robot.model
    out = np.zeros((levers.shape[0], model.nq, model.nq))
    for g, obj in enumerate(robot.collision_model.geometryObjects):
        chain = [model.joints[j].idx_q for j in model.supports[obj.parentJoint] if j > 0]  # root first
        for n, j in enumerate(chain):
            for k in chain[n + 1 :]:
                out[g, j, k] = levers[g, k]
    return out


def chord_deviation(times: np.ndarray, acceleration_bound: np.ndarray) -> np.ndarray:
    """Per joint, how far a curve sampled at ``times`` can leave the straight chords between its samples.

    ``acceleration_bound``: per joint, the largest |acceleration| along the curve. Linear interpolation
    error: ``a dt^2 / 8`` for the longest sample interval ``dt``. Pass it as ``deviation`` to
    :meth:`PathCertifier.certify_path` to certify the curve itself rather than its chords.
    """
    dt = float(np.max(np.diff(np.asarray(times, dtype=float)), initial=0.0))
    return np.abs(np.asarray(acceleration_bound, dtype=float)) * dt * dt / 8.0
