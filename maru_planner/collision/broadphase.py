"""Broad phase against large scenes: obstacles out of the robot's reach are dropped, the rest go in a tree.

- :func:`robot_reach`: the radius around the root frame's origin that no moving collision geometry
  can leave, whatever the configuration (joint offsets, prismatic travel and geometry sizes added up
  along each chain). An obstacle whose bounding sphere lies outside it can never be touched and is
  dropped when the scene is built (:meth:`~maru_planner.scene.Scene.obstacles_within`), so 100,000 far
  obstacles cost one pass per scene version, shared by its checkers, and nothing per check.
- :class:`SceneTree`: the reachable obstacles in a coal dynamic AABB tree, built once per scene
  version, and the robot's moving geometries in a second manager that pinocchio updates; one
  manager-vs-manager query per check (``collides``), plus the diagnostics ``colliding_pairs`` and
  ``nearest`` on AABB-filtered pairs. A security margin (``padding``) inflates the obstacles' boxes,
  so pairs within the margin reach the narrow phase.
Both builds tick a :class:`~maru_planner.scene.BuildClock` (the build's time budget).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from maru_planner.robot.model import RobotModel
from maru_planner.scene import BuildClock, Obstacle


def robot_reach(robot: RobotModel) -> float:
    """Radius (m) around the root origin containing every moving collision geometry at any configuration."""
    model = robot.model
    reach = np.zeros(model.njoints)
    for j in range(1, model.njoints):
        joint = model.joints[j]
        travel = 0.0
        if "Prismatic" in joint.shortname() or joint.shortname().startswith("JointModelP"):
            i = joint.idx_q
            travel = max(abs(model.lowerPositionLimit[i]), abs(model.upperPositionLimit[i]))
        reach[j] = reach[model.parents[j]] + np.linalg.norm(model.jointPlacements[j].translation) + travel
    radius = 0.0
    for obj in robot.collision_model.geometryObjects:
        if obj.parentJoint == 0:
            continue
        obj.geometry.computeLocalAABB()
        box = obj.geometry.aabb_local
        corner = np.maximum(np.abs(np.asarray(box.min_)), np.abs(np.asarray(box.max_)))
        size = reach[obj.parentJoint] + np.linalg.norm(obj.placement.translation) + np.linalg.norm(corner)
        radius = max(radius, float(size))
    return radius


def coal_transform(pose: np.ndarray) -> coal.Transform3s:
    pose = np.asarray(pose, dtype=float)
    return coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))


class SceneTree:
    """Reachable obstacles in a coal AABB tree, queried against the robot's moving geometries."""

    def __init__(self, robot: RobotModel, obstacles: list[Obstacle], padding: float, clock: BuildClock):
        self.model = robot.model
        self.names = [o.name for o in obstacles]
        self.padding = padding
        self.shapes, self.transforms, objects = [], [], []
        lo, hi = np.empty((len(obstacles), 3)), np.empty((len(obstacles), 3))
        for k, obstacle in enumerate(obstacles):
            clock.tick(k, "building the obstacle tree")
            shape, tf = obstacle.geometry(), coal_transform(obstacle.pose)
            obj = coal.CollisionObject(shape, tf)
            obj.getAABB().expand(padding)  # the margin's pairs must reach the narrow phase
            lo[k], hi[k] = obj.getAABB().min_, obj.getAABB().max_
            self.shapes.append(shape)
            self.transforms.append(tf)
            objects.append(obj)
        self.objects, self.lo, self.hi = objects, lo, hi
        self.tree = coal.DynamicAABBTreeCollisionManager()
        self.tree.registerObjects(objects)
        self.tree.setup()
        self.robot_geom = pin.GeometryModel()
        self.links = []
        for obj in robot.collision_model.geometryObjects:
            if obj.parentJoint != 0:  # fixed to the world: like the pair list, never tested against the scene
                self.robot_geom.addGeometryObject(obj)
                self.links.append(robot.model.frames[obj.parentFrame].name)
        self.robot_data = pin.GeometryData(self.robot_geom)
        self.robot_tree = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(
            self.model, self.robot_geom, self.robot_data
        )
        self.robot_objects = self.robot_tree.getManager()
        self.request = coal.CollisionRequest()
        self.request.security_margin = padding
        self.request.enable_contact = False

    @property
    def n_pairs(self) -> int:
        return self.robot_geom.ngeoms * len(self.names)

    def pair_names(self) -> list[tuple[str, str]]:
        return [(link, name) for link in self.links for name in self.names]

    def _place(self, data: pin.Data) -> None:
        """Robot geometry placements from ``data``'s forward kinematics (already computed)."""
        pin.updateGeometryPlacements(self.model, data, self.robot_geom, self.robot_data)
        self.robot_tree.update(False)

    def collides(self, data: pin.Data) -> bool:
        """Whether any moving robot geometry touches an obstacle (kinematics already in ``data``)."""
        self._place(data)
        callback = coal.CollisionCallBackDefault()
        callback.data.request.security_margin = self.padding
        callback.data.request.enable_contact = False
        self.tree.collide(self.robot_objects, callback)
        return callback.data.result.isCollision()

    def _candidates(self, gap: float) -> tuple[list[int], list[int], list[float]]:
        """(robot geometry, obstacle, box distance) lists of the pairs whose boxes are within ``gap``,
        nearest first (robot boxes as placed by the last ``_place``; obstacle boxes include the margin)."""
        boxes = [obj.getAABB() for obj in self.robot_tree.getCollisionObjects()]
        g_lo = np.array([b.min_ for b in boxes]).reshape(-1, 1, 3)
        g_hi = np.array([b.max_ for b in boxes]).reshape(-1, 1, 3)
        outside = np.maximum(np.maximum(self.lo[None] - g_hi, g_lo - self.hi[None]), 0.0)
        dist = np.linalg.norm(outside, axis=2)  # (robot geometries, obstacles)
        g, k = np.nonzero(dist <= gap)
        order = np.argsort(dist[g, k], kind="stable")
        return g[order].tolist(), k[order].tolist(), dist[g, k][order].tolist()

    def _pose(self, g: int) -> np.ndarray:
        return self.robot_data.oMg[g].homogeneous

    def colliding_pairs(self, data: pin.Data) -> list[tuple[str, str]]:
        """(link, obstacle) names of every colliding pair (kinematics already in ``data``)."""
        self._place(data)
        hits = []
        for g, k, _ in zip(*self._candidates(0.0)):
            robot_shape = self.robot_geom.geometryObjects[g].geometry
            result = coal.CollisionResult()
            if coal.collide(robot_shape, coal_transform(self._pose(g)), self.shapes[k], self.transforms[k],
                            self.request, result):  # fmt: skip
                hits.append((self.links[g], self.names[k]))
        return hits

    def nearest(self, data: pin.Data) -> tuple[tuple[str, str], float]:
        """Closest (link, obstacle) pair and its distance; pairs are tried nearest box first, until no box
        can beat the best distance found."""
        self._place(data)
        best, best_pair = np.inf, ("", "")
        request = coal.DistanceRequest()
        for g, k, box_distance in zip(*self._candidates(np.inf)):
            if box_distance >= best and box_distance > 0.0:  # overlapping boxes may still hide a deeper contact
                break
            result = coal.DistanceResult()
            robot_shape = self.robot_geom.geometryObjects[g].geometry
            d = coal.distance(robot_shape, coal_transform(self._pose(g)), self.shapes[k], self.transforms[k],
                              request, result)  # fmt: skip
            if d < best:
                best, best_pair = float(d), (self.links[g], self.names[k])
        return best_pair, best
