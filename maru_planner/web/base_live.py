"""The base side live in the browser: an occupancy grid or a BARN world under the base, its path, the elastic strip
and the laser points, each redrawn when a new one comes (``reactive_node``'s topics, through
``maru_planner/ros/plan_view_bridge.py``'s base view; or ``maru-view --barn N`` for the world alone).

A BARN world's cylinders are one instanced mesh (hundreds of cylinders, one scene node); a grid's occupied cells one
point cloud. The :meth:`LiveBaseView.show_pose`, :meth:`show_scan`, :meth:`show_path` and :meth:`show_strip` setters
are what a live source calls; each is one message to the page.
"""

from __future__ import annotations

import threading

import numpy as np
import trimesh
import viser

from maru_planner.base.grid import OccupancyGrid
from maru_planner.physics import barn_world
from maru_planner.reactive.scan import to_world

BASE_RADIUS = 0.25  # m: the disc drawn for the base
OBSTACLE_COLOR = (110, 160, 230)
PATH_COLOR, STRIP_COLOR, TRACE_COLOR, SCAN_COLOR = (40, 160, 60), (230, 120, 20), (90, 90, 220), (220, 30, 30)
TRACE_STEP = 0.05  # m: the driven trace gains a point when the base moved this far
TRACE_POINTS = 2000  # the trace keeps its latest points


def segments(points: np.ndarray, z: float) -> np.ndarray:
    """(k-1, 2, 3) line segments joining consecutive 2-D points at height ``z`` ((1, 2, 3) zeros for fewer than 2:
    viser wants one segment at least)."""
    points = np.asarray(points, dtype=np.float32).reshape(-1, 2)
    if len(points) < 2:
        return np.zeros((1, 2, 3), dtype=np.float32)
    xyz = np.column_stack([points, np.full(len(points), z, dtype=np.float32)])
    return np.stack([xyz[:-1], xyz[1:]], axis=1)


def flat_points(points: np.ndarray, z: float) -> np.ndarray:
    """(m, 2) -> (max(m, 1), 3) float32 at height ``z`` (viser wants one point at least)."""
    points = np.asarray(points, dtype=np.float32).reshape(-1, 2)
    xyz = np.zeros((max(len(points), 1), 3), dtype=np.float32)
    xyz[: len(points), :2] = points
    xyz[: len(points), 2] = z
    return xyz


def add_barn_world(server: viser.ViserServer, grid: np.ndarray) -> int:
    """World ``grid``'s cylinders (field and containment walls) as one instanced mesh; how many there are."""
    centres = barn_world.cylinder_centres(grid)
    mesh = trimesh.creation.cylinder(radius=barn_world.CYLINDER_RADIUS, height=barn_world.CYLINDER_HEIGHT, sections=12)
    positions = np.column_stack([centres, np.full(len(centres), barn_world.CYLINDER_HEIGHT / 2)]).astype(np.float32)
    wxyzs = np.tile(np.array([1.0, 0.0, 0.0, 0.0], dtype=np.float32), (len(centres), 1))
    server.scene.add_batched_meshes_simple(
        "/base/world", np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.int32), wxyzs, positions,
        batched_colors=OBSTACLE_COLOR, lod="off", cast_shadow=False, receive_shadow=False,
    )  # fmt: skip
    return len(centres)


def add_grid_map(server: viser.ViserServer, grid: OccupancyGrid) -> int:
    """The grid's occupied cells as a point cloud; how many there are."""
    cells = grid.cells_to_world(np.argwhere(grid.occupied))
    server.scene.add_point_cloud(
        "/base/map", flat_points(cells, 0.0), (60, 60, 60), point_size=grid.resolution, precision="float32"
    )
    return len(cells)


class LiveBaseView:
    """The base, its path, strip, laser points and driven trace over a grid or a BARN world (module doc)."""

    def __init__(
        self,
        server: viser.ViserServer,
        grid: OccupancyGrid | None = None,
        barn: np.ndarray | None = None,
        centre: tuple[float, float] = (0.0, 0.0),
    ):
        self.server = server
        scene = server.scene
        scene.configure_environment_map(None)
        scene.configure_default_lights(enabled=True, cast_shadow=False)
        if barn is not None:
            centre = (barn_world.START[0], barn_world.START[1] + 3.0)
        x0, y0 = centre
        server.initial_camera.position = (x0 - 6.0, y0 - 3.0, 7.0)
        server.initial_camera.look_at = (x0, y0, 0.0)
        scene.add_grid("/ground", 20.0, 20.0, cell_size=1.0, position=(x0, y0, 0.0), shadow_opacity=0.0)
        self.obstacles = add_barn_world(server, barn) if barn is not None else 0
        if barn is not None:
            scene.add_icosphere("/base/barn_goal", 0.1, PATH_COLOR, position=(*barn_world.GOAL, 0.1))
        self.obstacles += add_grid_map(server, grid) if grid is not None else 0
        self.base = scene.add_frame("/base/robot", show_axes=False)
        scene.add_cylinder("/base/robot/body", BASE_RADIUS, 0.2, (230, 150, 40), position=(0.0, 0.0, 0.1))
        scene.add_box("/base/robot/heading", (40, 40, 40), (BASE_RADIUS, 0.05, 0.05), position=(0.15, 0.0, 0.22))
        self._path = scene.add_line_segments("/base/path", segments(np.zeros((0, 2)), 0.01), PATH_COLOR, thickness=0.04)
        self._strip = scene.add_line_segments("/base/strip", segments(np.zeros((0, 2)), 0.03), STRIP_COLOR,
                                              thickness=0.03)  # fmt: skip
        self._trace = scene.add_line_segments("/base/trace", segments(np.zeros((0, 2)), 0.02), TRACE_COLOR,
                                              thickness=0.02)  # fmt: skip
        self._scan = scene.add_point_cloud("/base/scan", flat_points(np.zeros((0, 2)), 0.15), SCAN_COLOR,
                                           point_size=0.04, precision="float32")  # fmt: skip
        self._lock = threading.Lock()
        self.pose: np.ndarray | None = None  # (x, y, yaw) shown
        self.trace = np.zeros((0, 2))
        self.path = np.zeros((0, 2))
        self.strip = np.zeros((0, 2))
        self.scan_points = np.zeros((0, 2))  # world frame
        self.counts = {"poses": 0, "scans": 0, "paths": 0, "strips": 0}
        with server.gui.add_folder("Base (live)"):
            self.summary = server.gui.add_markdown(self._summary())

    def show_pose(self, x: float, y: float, yaw: float) -> None:
        """The base at (x, y, yaw); the trace grows when it moved :data:`TRACE_STEP`."""
        with self._lock:
            self.pose = np.array([x, y, yaw], dtype=float)
            self.counts["poses"] += 1
            grew = not len(self.trace) or np.hypot(*(self.trace[-1] - self.pose[:2])) >= TRACE_STEP
            if grew:
                self.trace = np.vstack([self.trace, self.pose[:2]])[-TRACE_POINTS:]
            trace = self.trace
        with self.server.atomic():
            self.base.position = (float(x), float(y), 0.0)
            self.base.wxyz = (float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2)))
            if grew:
                self._trace.points = segments(trace, 0.02)

    def show_scan(self, points: np.ndarray, in_base: bool = False) -> None:
        """Laser points (m, 2), in the world frame (``in_base``: in the base frame, placed by the shown pose)."""
        with self._lock:
            if in_base and self.pose is None:
                return  # nowhere to put them yet
            world = to_world(np.asarray(points, dtype=float).reshape(-1, 2), self.pose) if in_base else points
            self.scan_points = np.asarray(world, dtype=float).reshape(-1, 2)
            self.counts["scans"] += 1
        self._scan.points = flat_points(self.scan_points, 0.15)

    def show_path(self, points: np.ndarray) -> None:
        """The base path (k, 2)."""
        self.path = np.asarray(points, dtype=float).reshape(-1, 2)
        self.counts["paths"] += 1
        self._path.points = segments(self.path, 0.01)
        self.summary.content = self._summary()

    def show_strip(self, points: np.ndarray) -> None:
        """The elastic strip (k, 2)."""
        self.strip = np.asarray(points, dtype=float).reshape(-1, 2)
        self.counts["strips"] += 1
        self._strip.points = segments(self.strip, 0.03)

    def refresh_summary(self) -> None:
        self.summary.content = self._summary()

    def _summary(self) -> str:
        counts = ", ".join(f"{n} {what}" for what, n in self.counts.items())
        return f"{self.obstacles} obstacles; received {counts}; path of {len(self.path)} poses"
