"""The robot in a viser scene: its URDF's visual meshes (read by pinocchio + coal), one scene frame per link.

:func:`visual_parts` reads the URDF's ``<visual>`` geometry on the full (unreduced) model and ties each part to
its parent frame by name, so the parts follow the planning model (whose locked joints are frames) through
:meth:`RobotView.show`. A URDF without visual geometry is drawn from its collision geometry.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import trimesh
import viser

from maru_planner.collision.sphere_model import cache_dir as sphere_cache_dir
from maru_planner.robot import RobotModel
from maru_planner.robot.robot_profile import profile
from maru_planner.runtime import RobotSource

ROOT = "/robot"
MESH_CELL = 0.006  # m: a detailed mesh's vertices closer than this merge (Panda: 135k triangles -> 37k)
SIMPLIFY_ABOVE = 2000  # triangles: smaller meshes (primitives, coarse parts) are drawn as they are
DEFAULT_COLOR = (200, 200, 210)
PARTS_CACHE_VERSION = 1  # bump when what a kept part holds changes


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
    """The visual meshes of ``source``'s URDF (its collision geometry when it has no visuals), simplified; kept
    on disk (:func:`parts_cache_path`): reading and simplifying Panda's meshes takes ~2.5 s, the kept copy ~10 ms."""
    urdf, package_dirs = source_files(source)
    path = parts_cache_path(urdf, package_dirs)
    cached = _load_parts(path)
    if cached is not None:
        return cached
    parts, mesh_files = read_parts(urdf, package_dirs)
    _save_parts(path, parts, mesh_files)
    return parts


def read_parts(urdf: Path, package_dirs: list[str]) -> tuple[list[VisualPart], list[str]]:
    """The parts read from the URDF's meshes, and the mesh files they came from."""
    model = pin.buildModelFromUrdf(str(urdf))
    geometry = pin.buildGeomFromUrdf(model, str(urdf), pin.VISUAL, package_dirs=package_dirs)
    if not geometry.geometryObjects:
        geometry = pin.buildGeomFromUrdf(model, str(urdf), pin.COLLISION, package_dirs=package_dirs)
    parts, mesh_files = [], []
    for item in geometry.geometryObjects:
        triangles = _triangles(item.geometry)
        if triangles is None:
            continue
        if item.meshPath and os.path.isfile(item.meshPath):
            mesh_files.append(str(item.meshPath))
        frame = model.frames[item.parentFrame]
        local = (frame.placement.inverse() * item.placement).homogeneous
        vertices, faces = triangles  # coal applied the URDF's mesh scale
        if len(faces) > SIMPLIFY_ABOVE:
            vertices, faces = simplified(vertices, faces, MESH_CELL)
        if np.linalg.det(np.diag(np.asarray(item.meshScale, dtype=float))) < 0:
            faces = faces[:, ::-1].copy()  # a mirrored mesh: keep its faces outward
        parts.append(VisualPart(frame.name, local, vertices, faces, _color(item.meshColor)))
    return parts, mesh_files


def parts_cache_path(urdf: Path, package_dirs: list[str]) -> Path:
    """Where the simplified parts of ``urdf`` are kept (keyed by its text, package directories and simplification)."""
    key = hashlib.sha1(f"{PARTS_CACHE_VERSION}|{MESH_CELL}|{SIMPLIFY_ABOVE}|{package_dirs}|".encode())
    key.update(Path(urdf).read_bytes())
    return sphere_cache_dir().parent / "view_meshes" / f"{key.hexdigest()}.npz"


def _mesh_stamps(files: list[str]) -> str:
    return json.dumps([[f, os.stat(f).st_mtime_ns, os.stat(f).st_size] for f in files])


def _save_parts(path: Path, parts: list[VisualPart], mesh_files: list[str]) -> None:
    """Keep ``parts`` at ``path`` (quietly nothing when the cache cannot be written)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
        np.savez(
            tmp,
            frames=np.array([p.frame for p in parts], dtype=str),
            locals=np.array([p.local for p in parts]).reshape(-1, 4, 4),
            colors=np.array([p.color for p in parts], dtype=np.int32).reshape(-1, 3),
            vertex_counts=np.array([len(p.vertices) for p in parts], dtype=np.int64),
            face_counts=np.array([len(p.faces) for p in parts], dtype=np.int64),
            vertices=np.concatenate([p.vertices for p in parts]) if parts else np.zeros((0, 3), np.float32),
            faces=np.concatenate([p.faces for p in parts]) if parts else np.zeros((0, 3), np.int32),
            stamps=np.array(_mesh_stamps(mesh_files)),
        )
        os.replace(tmp, path)
    except OSError:
        pass


def _load_parts(path: Path) -> list[VisualPart] | None:
    """The parts kept at ``path``; None when there are none or a mesh file changed since."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if _mesh_stamps(_stamped_files(str(data["stamps"]))) != str(data["stamps"]):
                return None
            vertex_ends, face_ends = np.cumsum(data["vertex_counts"]), np.cumsum(data["face_counts"])
            vertices, faces = data["vertices"], data["faces"]
            return [
                VisualPart(str(frame), local, vertices[v_end - nv : v_end], faces[f_end - nf : f_end],
                           (int(color[0]), int(color[1]), int(color[2])))
                for frame, local, color, v_end, nv, f_end, nf in zip(
                    data["frames"], data["locals"], data["colors"], vertex_ends, data["vertex_counts"], face_ends,
                    data["face_counts"], strict=True,
                )
            ]  # fmt: skip
    except (OSError, ValueError, KeyError):
        return None


def _stamped_files(stamps: str) -> list[str]:
    """The mesh files named in a cache's stamps."""
    return [entry[0] for entry in json.loads(stamps)]


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

    def set_visible(self, visible: bool) -> None:
        """Show or hide the whole robot (its link frames carry its meshes)."""
        with self._server.atomic():
            for handle in self._frames.values():
                handle.visible = visible

    def show(self, q: np.ndarray) -> None:
        """Pose every link at configuration ``q`` (one message batch)."""
        model, data = self.robot.model, self.robot.model.createData()
        pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
        with self._server.atomic():
            for name, handle in self._frames.items():
                wxyz, position = wxyz_position(data.oMf[self._frame_ids[name]].homogeneous)
                handle.wxyz, handle.position = wxyz, position
        self.q = np.array(q, dtype=float)
