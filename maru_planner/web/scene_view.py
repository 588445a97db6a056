"""A scene's obstacles in a viser scene under ``/scene``; attached objects ride on their link's frame.

Spheres and cylinders are viser primitives; boxes and any other shape of the shape table are drawn from their
``faces`` (fan-triangulated polygons), so a new obstacle type shows up without a change here. A box is a mesh
rather than viser's box: its own vertices per face look the same (flat), and it draws with the robot meshes'
shader, one compile less (~0.1 s of a software-WebGL page's first frame).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import viser

from maru_planner.scene import Obstacle, Scene
from maru_planner.web.robot_view import wxyz_position

ROOT = "/scene"
OBSTACLE_COLOR = (110, 160, 230)
ATTACHED_COLOR = (240, 170, 60)
LinkNode = Callable[[str], str]  # link name -> its scene frame's name


def node_name(name: str) -> str:
    """A scene-tree-safe name for an object (a '/' would make it a child)."""
    return name.replace("/", "|")


def faces_mesh(obstacle: Obstacle) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of an obstacle's polygons, in its own frame."""
    vertices: list[np.ndarray] = []
    triangles: list[list[int]] = []
    for polygon in obstacle.spec.faces(obstacle.dimensions):
        base = sum(len(v) for v in vertices)
        vertices.append(np.asarray(polygon, dtype=np.float32))
        triangles += [[base, base + k, base + k + 1] for k in range(1, len(polygon) - 1)]
    return np.concatenate(vertices), np.asarray(triangles, dtype=np.int32)


def outward(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``faces`` with each triangle turned to face away from the origin (a convex shape about its own frame)."""
    corners = vertices[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    inward = np.einsum("ij,ij->i", normals, corners.mean(axis=1)) < 0
    turned = faces.copy()
    turned[inward] = turned[inward][:, ::-1]
    return turned


def add_obstacle(
    server: viser.ViserServer, name: str, obstacle: Obstacle, color: tuple[int, int, int], opacity: float | None = None
) -> viser.SceneNodeHandle:
    """Draw ``obstacle`` as scene node ``name`` at its pose."""
    wxyz, position = wxyz_position(obstacle.pose)
    scene = server.scene
    d = obstacle.dimensions
    if obstacle.type == "sphere":
        return scene.add_icosphere(name, d["radius"], color, opacity=opacity, wxyz=wxyz, position=position)
    if obstacle.type == "cylinder":
        # viser's cylinder lies along its local z like ours
        return scene.add_cylinder(name, d["radius"], d["length"], color, opacity=opacity, wxyz=wxyz, position=position)
    vertices, faces = faces_mesh(obstacle)
    if obstacle.type == "box":  # (module doc) no shadows, as the robot's meshes
        return scene.add_mesh_simple(name, vertices, outward(vertices, faces), color=color, opacity=opacity,
                                     wxyz=wxyz, position=position, cast_shadow=False, receive_shadow=False)  # fmt: skip
    return scene.add_mesh_simple(
        name, vertices, faces, color=color, opacity=opacity, side="double", wxyz=wxyz, position=position
    )


class SceneView:
    """Draws scene dicts (:meth:`Scene.to_dict`): obstacles under ``/scene``, attached objects on their links."""

    def __init__(self, server: viser.ViserServer, link_node: LinkNode):
        self._server = server
        self._link_node = link_node
        self._nodes: list[viser.SceneNodeHandle] = []
        self.scene = Scene()

    def show(self, scene: Scene | dict) -> None:
        """Replace what is drawn by ``scene``."""
        self.scene = scene if isinstance(scene, Scene) else Scene.from_dict(scene)
        with self._server.atomic():
            for node in self._nodes:
                node.remove()
            self._nodes = [
                add_obstacle(self._server, f"{ROOT}/{node_name(o.name)}", o, OBSTACLE_COLOR)
                for o in self.scene.obstacles.values()
            ]
            for item in self.scene.attached.values():
                name = f"{self._link_node(item.link)}/attached_{node_name(item.name)}"
                self._nodes.append(add_obstacle(self._server, name, item.obstacle, ATTACHED_COLOR))

    @property
    def obstacle_names(self) -> list[str]:
        return list(self.scene.obstacles)
