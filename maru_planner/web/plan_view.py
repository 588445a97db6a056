"""What a plan looks like in the browser: the robot, its scene, its start state and a trajectory played back with
a time scrubber, the plan's certified clearance and statistics, or a failure's one-line message.

:class:`PlanView` is display only, so anything that plans can drive it: ``maru-view`` (:mod:`~maru_planner.web.server`)
and, for its ``view`` option, ``planning_node`` (``show_scene`` on a scene change, ``show_start`` on
``/joint_states``, ``show_result`` with each plan it serves). Its methods are thread-safe.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Mapping

import numpy as np
import viser

from maru_planner.planning.types import MotionResult
from maru_planner.robot import RobotModel
from maru_planner.runtime import RobotSource
from maru_planner.scene import Scene
from maru_planner.trajectory.trajectory import Trajectory
from maru_planner.web.robot_view import RobotView, visual_parts
from maru_planner.web.scene_view import SceneView
from maru_planner.web.serving import DEFAULT_HOST, serve

FRAME_PERIOD = 1.0 / 30.0  # s between played frames


def trajectory_state(trajectory: Trajectory, start: np.ndarray, columns: np.ndarray, t: float) -> np.ndarray:
    """The full configuration at time ``t``: ``start`` with the trajectory's joints (``columns`` of q) interpolated."""
    q = np.array(start, dtype=float)
    times = trajectory.times
    for k, column in enumerate(columns):
        q[column] = np.interp(t, times, trajectory.positions[:, k])
    return q


def result_summary(result: MotionResult) -> str:
    """Markdown lines of a plan: status and message; when it succeeded, clearance and the main statistics."""
    if not result.success:
        return f"**{result.status.value}**: {result.message}"
    stats = result.stats
    clearance = "n/a" if not math.isfinite(stats.min_clearance) else f"{stats.min_clearance * 1000:.1f} mm"
    duration = result.trajectory.duration if result.trajectory is not None else 0.0
    return "\n\n".join(
        [
            f"**SUCCESS** ({stats.planner_id}): {result.message}",
            f"certified: {'yes' if stats.certified else 'no'}, clearance {clearance}",
            f"planning {stats.total_time * 1000:.0f} ms, {stats.waypoints} waypoints, "
            f"length {stats.path_length:.3f} rad, motion {duration:.2f} s",
        ]
    )


class PlanView:
    """The robot, scene and plans of one robot in a viser server (module doc)."""

    def __init__(self, server: viser.ViserServer, robot: RobotModel, source: RobotSource):
        self.server = server
        self.robot = robot
        server.initial_camera.position = (0.6, -2.2, 1.6)
        server.initial_camera.look_at = (0.35, 0.0, 0.7)
        # no image-based lighting and no shadow maps: a software-WebGL page draws its first frame in about a second
        server.scene.configure_environment_map(None)
        server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        server.scene.add_light_ambient("/ambient", intensity=1.5)
        server.scene.add_grid("/ground", 4.0, 4.0, cell_size=0.25, shadow_opacity=0.0)
        self.robot_view = RobotView(server, robot, visual_parts(source))
        self.scene_view = SceneView(server, self.robot_view.link_node)
        self._lock = threading.Lock()
        self._playback = 0  # bumped to stop the playing thread
        self._playing = -1  # the ticket of the thread that is playing (-1: none)
        self.trajectory: Trajectory | None = None
        self.start = robot.neutral()
        self._columns = np.zeros(0, dtype=int)
        self.frames_shown = 0  # trajectory frames sent since the last plan (the player's progress)
        self.first_frame_time: float | None = None  # time.monotonic() of the last plan's first frame
        with server.gui.add_folder("Plan") as self.folder:
            self.status = server.gui.add_markdown("no plan yet")
            self.scrubber = server.gui.add_slider("time (s)", 0.0, 1.0, 0.01, 0.0, disabled=True)
            self.replay = server.gui.add_button("Replay", disabled=True)
        self.scrubber.on_update(self._on_scrub)
        self.replay.on_click(lambda _: self.play())

    @classmethod
    def serve(cls, source: RobotSource, robot: RobotModel | None = None, host: str = DEFAULT_HOST, port: int = 8080
              ) -> PlanView:  # fmt: skip
        """A view on its own server (``planning_node``'s ``view`` option: ``runtime.source``, ``runtime.robot``);
        InvalidRequest if ``host`` is not this machine's. :attr:`url` is where it is; :meth:`close` stops it."""
        return cls(serve(host, port), robot if robot is not None else source.load(), source)

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"

    def close(self) -> None:
        with self._lock:
            self._playback += 1
        self.server.stop()

    # ------------------------------------------------------------ what the planner side calls
    def show_scene(self, scene: Scene | dict) -> None:
        self.scene_view.show(scene)

    def show_start(self, start: np.ndarray | Mapping[str, float]) -> None:
        """Show the robot at ``start`` (a configuration, or joint values by name; missing joints keep theirs)."""
        q = self._configuration(start)
        with self._lock:
            self._playback += 1
            self.start = q
        self.robot_view.show(q)

    def show_result(self, result: MotionResult, start: np.ndarray | Mapping[str, float] | None = None) -> None:
        """Show a plan's outcome: its summary, and a successful plan's trajectory played from ``start``."""
        self.status.content = result_summary(result)
        if result.success and result.trajectory is not None:
            self.show_plan(result.trajectory, start)

    def show_failure(self, message: str) -> None:
        self.status.content = f"**FAILED**: {message}"

    def show_plan(self, trajectory: Trajectory, start: np.ndarray | Mapping[str, float] | None = None) -> None:
        """Play ``trajectory`` (its joints move, the others stay at ``start``, default: the shown start)."""
        with self._lock:
            if start is not None:
                self.start = self._configuration(start)
            self.trajectory = trajectory
            self._columns = self.robot.joint_indices(trajectory.joint_names)
            self.frames_shown, self.first_frame_time = 0, None
        duration = max(trajectory.duration, 1e-3)
        self.scrubber.max = duration
        self.scrubber.step = duration / 200.0
        self.scrubber.disabled = self.replay.disabled = False
        self.play()

    def play(self) -> None:
        """Play the current trajectory from its start in a thread (a new call or a scrub stops it)."""
        with self._lock:
            self._playback += 1
            ticket = self._playing = self._playback
        threading.Thread(target=self._play, args=(ticket,), daemon=True, name="maru-view-play").start()

    @property
    def playing(self) -> bool:
        """Whether a trajectory is being played now."""
        return self._playing == self._playback

    def state_at(self, t: float) -> np.ndarray:
        """The configuration the trajectory puts the robot in at ``t`` (the start when there is none)."""
        with self._lock:
            if self.trajectory is None:
                return self.start.copy()
            return trajectory_state(self.trajectory, self.start, self._columns, t)

    def wait_played(self, timeout: float) -> bool:
        """Whether the playing trajectory reached its end within ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            trajectory = self.trajectory
            if trajectory is not None and self.scrubber.value >= self.scrubber.max and self.frames_shown > 0:
                return True
            time.sleep(0.02)
        return False

    # ------------------------------------------------------------ inside
    def _configuration(self, values: np.ndarray | Mapping[str, float]) -> np.ndarray:
        if isinstance(values, Mapping):
            q = self.robot_view.q.copy()
            names = [n for n in values if n in self.robot.joint_names]
            q[self.robot.joint_indices(names)] = [float(values[n]) for n in names]
            return q
        return np.asarray(values, dtype=float).copy()

    def _play(self, ticket: int) -> None:
        trajectory, t0 = self.trajectory, time.monotonic()
        try:
            while trajectory is not None and ticket == self._playback:
                t = min(time.monotonic() - t0, trajectory.duration)
                self._show_time(t)
                if t >= trajectory.duration:
                    return
                time.sleep(FRAME_PERIOD)
        finally:
            if self._playing == ticket:
                self._playing = -1

    def _show_time(self, t: float) -> None:
        q = self.state_at(t)
        self.robot_view.show(q)
        self.scrubber.value = min(t, self.scrubber.max)  # type: ignore[misc]  # (viser types a settable value read-only)
        if self.frames_shown == 0:
            self.first_frame_time = time.monotonic()
        self.frames_shown += 1

    def _on_scrub(self, event: viser.GuiEvent) -> None:
        if event.client is None:  # the player moved it
            return
        with self._lock:
            self._playback += 1
        self.robot_view.show(self.state_at(float(self.scrubber.value)))
