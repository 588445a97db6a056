"""A scene's obstacles in a viser scene under ``/scene``; attached objects ride on their link's frame.

Boxes, spheres and cylinders are viser primitives; any other shape of the shape table is drawn from its
``faces`` (fan-triangulated polygons), so a new obstacle type shows up without a change here.
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


def add_obstacle(
    server: viser.ViserServer, name: str, obstacle: Obstacle, color: tuple[int, int, int], opacity: float | None = None
) -> viser.SceneNodeHandle:
    """Draw ``obstacle`` as scene node ``name`` at its pose."""
    wxyz, position = wxyz_position(obstacle.pose)
    scene = server.scene
    d = obstacle.dimensions
    if obstacle.type == "box":
        return scene.add_box(name, color, tuple(d["size"]), opacity=opacity, wxyz=wxyz, position=position)
    if obstacle.type == "sphere":
        return scene.add_icosphere(name, d["radius"], color, opacity=opacity, wxyz=wxyz, position=position)
    if obstacle.type == "cylinder":
        # viser's cylinder lies along its local z like ours
        return scene.add_cylinder(name, d["radius"], d["length"], color, opacity=opacity, wxyz=wxyz, position=position)
    vertices, faces = faces_mesh(obstacle)
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
