"""The robot in a viser scene: its URDF's visual meshes (read by pinocchio + coal), one scene frame per link.

:func:`visual_parts` reads the URDF's ``<visual>`` geometry on the full (unreduced) model and ties each part to
its parent frame by name, so the parts follow the planning model (whose locked joints are frames) through
:meth:`RobotView.show`. A URDF without visual geometry is drawn from its collision geometry.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import trimesh
import viser

from maru_planner.robot import RobotModel
from maru_planner.robot.robot_profile import profile
from maru_planner.runtime import RobotSource

ROOT = "/robot"
MESH_CELL = 0.006  # m: a detailed mesh's vertices closer than this merge (Panda: 135k triangles -> 37k)
SIMPLIFY_ABOVE = 2000  # triangles: smaller meshes (primitives, coarse parts) are drawn as they are
DEFAULT_COLOR = (200, 200, 210)


@dataclass(frozen=True)
class VisualPart:
    """One mesh of the robot: its parent frame's name, its pose in that frame, triangles, colour."""

    frame: str
    local: np.ndarray  # 4x4 in the frame
    vertices: np.ndarray  # (n, 3)
    faces: np.ndarray  # (m, 3) int
    color: tuple[int, int, int]


def source_files(source: RobotSource) -> tuple[Path, list[str]]:
    """The URDF of ``source`` and its package directories."""
    if source.profile:
        files = profile(source.profile).files()
        return files.urdf, [str(p) for p in files.package_dirs]
    return Path(source.urdf), list(source.package_dirs)


def _triangles(geometry: coal.CollisionGeometry) -> tuple[np.ndarray, np.ndarray] | None:
    """(vertices, faces) of a coal shape, None for shapes without a picture here (planes, octrees)."""
    if isinstance(geometry, coal.BVHModelBase):
        tris = (geometry.tri_indices(i) for i in range(geometry.num_tris))
        faces = np.array([[t[0], t[1], t[2]] for t in tris], dtype=np.int32).reshape(-1, 3)
        return np.asarray(geometry.vertices(), dtype=np.float32), faces
    mesh: trimesh.Trimesh
    if isinstance(geometry, coal.Box):
        mesh = trimesh.creation.box(extents=2.0 * np.asarray(geometry.halfSide))
    elif isinstance(geometry, coal.Sphere):
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=geometry.radius)
    elif isinstance(geometry, coal.Cylinder):
        mesh = trimesh.creation.cylinder(radius=geometry.radius, height=2.0 * geometry.halfLength)
    elif isinstance(geometry, coal.Capsule):
        mesh = trimesh.creation.capsule(height=2.0 * geometry.halfLength, radius=geometry.radius)
    else:
        return None
    return np.asarray(mesh.vertices, dtype=np.float32), np.asarray(mesh.faces, dtype=np.int32)


def simplified(vertices: np.ndarray, faces: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertex clustering: the vertices of each ``cell``-sized grid cube merged at their mean, the triangles that
    collapse dropped. A software-WebGL page draws the robot's first frame that much sooner."""
    keys = np.floor(vertices / cell).astype(np.int64)
    _, cluster, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    cluster = cluster.reshape(-1)
    sums = np.zeros((counts.size, 3))
    np.add.at(sums, cluster, vertices)
    merged = cluster[faces]
    kept = merged[(merged[:, 0] != merged[:, 1]) & (merged[:, 1] != merged[:, 2]) & (merged[:, 0] != merged[:, 2])]
    return (sums / counts[:, None]).astype(np.float32), kept.astype(np.int32)


def _color(rgba: np.ndarray) -> tuple[int, int, int]:
    rgb = np.clip(np.asarray(rgba, dtype=float)[:3], 0.0, 1.0)
    r, g, b = (int(round(255 * c)) for c in rgb)
    return (r, g, b) if (r, g, b) != (229, 229, 229) else DEFAULT_COLOR  # pinocchio's default grey: ours


def visual_parts(source: RobotSource) -> list[VisualPart]:
    """The visual meshes of ``source``'s URDF (its collision geometry when it has no visuals)."""
    urdf, package_dirs = source_files(source)
    model = pin.buildModelFromUrdf(str(urdf))
    geometry = pin.buildGeomFromUrdf(model, str(urdf), pin.VISUAL, package_dirs=package_dirs)
    if not geometry.geometryObjects:
        geometry = pin.buildGeomFromUrdf(model, str(urdf), pin.COLLISION, package_dirs=package_dirs)
    parts = []
    for item in geometry.geometryObjects:
        triangles = _triangles(item.geometry)
        if triangles is None:
            continue
        frame = model.frames[item.parentFrame]
        local = (frame.placement.inverse() * item.placement).homogeneous
        vertices, faces = triangles  # coal applied the URDF's mesh scale
        if len(faces) > SIMPLIFY_ABOVE:
            vertices, faces = simplified(vertices, faces, MESH_CELL)
        if np.linalg.det(np.diag(np.asarray(item.meshScale, dtype=float))) < 0:
            faces = faces[:, ::-1].copy()  # a mirrored mesh: keep its faces outward
        parts.append(VisualPart(frame.name, local, vertices, faces, _color(item.meshColor)))
    return parts


def wxyz_position(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """viser's (quaternion w, x, y, z; position) of a 4x4 pose."""
    quat = pin.Quaternion(np.asarray(pose[:3, :3], dtype=float))
    return np.array([quat.w, quat.x, quat.y, quat.z]), np.asarray(pose[:3, 3], dtype=float)


def pose_of(wxyz: np.ndarray, position: np.ndarray) -> np.ndarray:
    """The 4x4 pose of viser's (wxyz, position)."""
    w, x, y, z = (float(v) for v in wxyz)
    pose = np.eye(4)
    pose[:3, :3] = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
    pose[:3, 3] = np.asarray(position, dtype=float)
    return pose


class RobotView:
    """The robot drawn under ``/robot``: one scene frame per link carrying its meshes; :meth:`show` poses it."""

    def __init__(self, server: viser.ViserServer, robot: RobotModel, parts: list[VisualPart]):
        self.robot = robot
        self._server = server
        known = [p for p in parts if robot.model.existFrame(p.frame)]
        self._frames: dict[str, viser.FrameHandle] = {}
        self._frame_ids: dict[str, int] = {}
        for n, part in enumerate(known):
            if part.frame not in self._frames:
                self._frames[part.frame] = server.scene.add_frame(f"{ROOT}/{part.frame}", show_axes=False)
                self._frame_ids[part.frame] = robot.frame_id(part.frame)
            wxyz, position = wxyz_position(part.local)
            server.scene.add_mesh_simple(
                f"{ROOT}/{part.frame}/part{n}",
                part.vertices,
                part.faces,
                color=part.color,
                wxyz=wxyz,
                position=position,
                cast_shadow=False,  # shadows double the draw cost, and software WebGL pays it in full
                receive_shadow=False,
            )
        self.q = robot.neutral()
        self.show(self.q)

    def link_node(self, link: str) -> str:
        """The scene name of ``link``'s frame (made on first use for a link without meshes)."""
        if link not in self._frames and self.robot.model.existFrame(link):
            self._frames[link] = self._server.scene.add_frame(f"{ROOT}/{link}", show_axes=False)
            self._frame_ids[link] = self.robot.frame_id(link)
            self.show(self.q)
        return f"{ROOT}/{link}"

    def show(self, q: np.ndarray) -> None:
        """Pose every link at configuration ``q`` (one message batch)."""
        model, data = self.robot.model, self.robot.model.createData()
        pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
        with self._server.atomic():
            for name, handle in self._frames.items():
                wxyz, position = wxyz_position(data.oMf[self._frame_ids[name]].homogeneous)
                handle.wxyz, handle.position = wxyz, position
        self.q = np.array(q, dtype=float)
