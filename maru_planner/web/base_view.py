"""The base side in the browser: a run replayed from a bag (``maru-view --bag DIR [--map YAML]``).

:func:`read_base_run` takes ``/odom`` (the base's poses), ``/scan`` (laser points, placed in the world by the
pose at their time and the ``base_link`` -> laser transform of ``/tf``), ``/plan`` (the base path) and
``/goal_pose`` from a rosbag2 bag; :class:`BaseView` draws the occupancy grid (a map YAML), the path, the driven
trace, the base as a disc and the laser points of the chosen moment, with a time scrubber and "Play".
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import viser

from maru_planner.bag.rosbag_io import BagError, read_messages
from maru_planner.bag.tf import planar_pose_of
from maru_planner.base.grid import OccupancyGrid
from maru_planner.reactive.scan import LaserScanData, scan_to_points, to_world
from maru_planner.web.base_live import add_barn_world

BASE_RADIUS = 0.25  # m: the disc drawn for the base
TOPICS = ("/odom", "/scan", "/plan", "/goal_pose", "/tf")


@dataclass
class BaseRun:
    """A base run: poses (x, y, yaw) at ``times`` (s from the bag's start), laser points per scan, path, goal."""

    times: np.ndarray
    poses: np.ndarray
    scan_times: np.ndarray
    scan_points: list[np.ndarray]  # (m, 2) in the odom frame, one per scan
    path: np.ndarray  # (k, 2)
    goal: np.ndarray | None  # (x, y)

    @property
    def duration(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0

    def pose_at(self, t: float) -> np.ndarray:
        """The latest recorded pose at ``t``."""
        k = int(np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 1))
        return self.poses[k]

    def points_at(self, t: float) -> np.ndarray:
        """The latest scan's points at ``t`` (none before the first scan)."""
        k = int(np.searchsorted(self.scan_times, t, side="right") - 1)
        return self.scan_points[k] if k >= 0 else np.zeros((0, 2))


def _odom_pose(message: Any) -> tuple[float, float, float]:
    pose = message.pose.pose
    q = pose.orientation
    yaw = float(np.arctan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z)))
    return float(pose.position.x), float(pose.position.y), yaw


def read_base_run(bag: str | Path) -> BaseRun:
    """The run recorded in ``bag`` (BagError naming the bag if it has no ``/odom``)."""
    start: int | None = None
    times, poses = [], []
    scans: list[tuple[float, Any]] = []
    laser = (0.0, 0.0, 0.0)
    path, goal = np.zeros((0, 2)), None
    for record in read_messages(bag, TOPICS):
        start = record.timestamp_ns if start is None else start
        t = (record.timestamp_ns - start) / 1e9
        message: Any = record.decode()
        if record.topic == "/odom":
            times.append(t)
            poses.append(_odom_pose(message))
        elif record.topic == "/scan":
            scans.append((t, message))
        elif record.topic == "/tf":
            for transform in message.transforms:
                if transform.header.frame_id == "base_link" and "laser" in transform.child_frame_id:
                    laser = planar_pose_of(transform)
        elif record.topic == "/plan":
            path = np.array([[p.pose.position.x, p.pose.position.y] for p in message.poses]).reshape(-1, 2)
        else:
            goal = np.array([message.pose.position.x, message.pose.position.y])
    if not times:
        raise BagError(f"{bag}: no /odom messages: nothing to replay")
    run = BaseRun(np.array(times), np.array(poses), np.array([t for t, _ in scans]), [], path, goal)
    for t, msg in scans:
        scan = LaserScanData(msg.angle_min, msg.angle_increment, msg.ranges, msg.range_min, msg.range_max)
        run.scan_points.append(to_world(scan_to_points(scan, laser, max_range=scan.range_max), run.pose_at(t)))
    return run


def _segments(points: np.ndarray, z: float) -> np.ndarray:
    """(k-1, 2, 3) line segments joining consecutive 2-D points at height ``z``."""
    xyz = np.column_stack([points, np.full(len(points), z)])
    return np.stack([xyz[:-1], xyz[1:]], axis=1)


class BaseView:
    """A base run in a viser server (module doc)."""

    def __init__(
        self, server: viser.ViserServer, run: BaseRun, grid: OccupancyGrid | None = None, barn: np.ndarray | None = None
    ):
        self.server, self.run = server, run
        server.scene.configure_environment_map(None)
        server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        x0, y0 = (float(v) for v in run.poses[0, :2])
        server.initial_camera.position = (x0 - 1.0, y0 - 4.0, 4.0)
        server.initial_camera.look_at = (x0 + 2.0, y0, 0.0)
        server.scene.add_grid("/ground", 20.0, 20.0, cell_size=1.0, position=(x0, y0, 0.0), shadow_opacity=0.0)
        self.map_cells = add_barn_world(server, barn) if barn is not None else 0
        if grid is not None:
            cells = grid.cells_to_world(np.argwhere(grid.occupied))
            self.map_cells = len(cells)
            points = np.column_stack([cells, np.zeros(len(cells))])
            server.scene.add_point_cloud(
                "/base/map", points, (60, 60, 60), point_size=grid.resolution, precision="float32"
            )
        if len(run.path) > 1:
            server.scene.add_line_segments("/base/path", _segments(run.path, 0.01), (40, 160, 60), thickness=0.04)
        if len(run.poses) > 1:
            trace = _segments(run.poses[:, :2], 0.02)
            server.scene.add_line_segments("/base/trace", trace, (90, 90, 220), thickness=0.02)
        if run.goal is not None:
            server.scene.add_icosphere("/base/goal", 0.1, (40, 160, 60), position=(*run.goal, 0.1))
        self.base = server.scene.add_frame("/base/robot", show_axes=False)
        server.scene.add_cylinder("/base/robot/body", BASE_RADIUS, 0.2, (230, 150, 40), position=(0.0, 0.0, 0.1))
        server.scene.add_box("/base/robot/heading", (40, 40, 40), (BASE_RADIUS, 0.05, 0.05), position=(0.15, 0, 0.22))
        self.scan = server.scene.add_point_cloud(
            "/base/scan", np.zeros((1, 3)), (220, 30, 30), point_size=0.04, precision="float32"
        )
        with server.gui.add_folder("Base run"):
            self.scrubber = server.gui.add_slider("time (s)", 0.0, max(run.duration, 1e-3), 0.01, 0.0)
            self.play_button = server.gui.add_button("Play")
            self.summary = server.gui.add_markdown(
                f"{len(run.times)} poses, {len(run.scan_points)} scans, path of {len(run.path)} poses, "
                f"{run.duration:.1f} s"
            )
        self._playback = 0
        self.scrubber.on_update(lambda _: self.show_time(float(self.scrubber.value)))
        self.play_button.on_click(lambda _: self.play())
        self.shown_time = 0.0
        self.show_time(0.0)

    def show_time(self, t: float) -> None:
        """The base and its laser points at ``t``."""
        x, y, yaw = self.run.pose_at(t)
        points = self.run.points_at(t)
        with self.server.atomic():
            self.base.position = (float(x), float(y), 0.0)
            self.base.wxyz = (float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2)))
            xyz = np.zeros((max(len(points), 1), 3), dtype=np.float32)  # viser wants one point at least
            xyz[: len(points), :2] = points
            xyz[: len(points), 2] = 0.15
            self.scan.points = xyz
        self.shown_time = t

    def play(self) -> None:
        """Replay the run in real time from its start (a new Play restarts it)."""
        self._playback += 1
        threading.Thread(target=self._play, args=(self._playback,), daemon=True, name="maru-view-base").start()

    def _play(self, ticket: int) -> None:
        t0 = time.monotonic()
        while ticket == self._playback:
            t = min(time.monotonic() - t0, self.run.duration)
            self.scrubber.value = t  # type: ignore[misc]  # (viser types a settable value read-only)
            if t >= self.run.duration:
                return
            time.sleep(1.0 / 30.0)
