"""``maru-view``'s application: a viser server showing one robot and its scene, planning through a
:class:`~maru_planner.runtime.PlanningRuntime` what the side panel and the goal gizmos ask for.

The page is served at once (robot and scene drawn from the robot model). The controls (the side panel's folders and
the goal gizmos) and then the runtime (workers, warm-up) come once the first page is up (its camera reported, then
its first frame drawn): with software WebGL, the panel's ~40 inputs (React) and the gizmos' three shaders cost the
page ~0.1-0.15 s of CPU before the robot's first frame (measured), and a warm-up that runs while the browser compiles
viser's client and draws the first frame makes the page ~1-2 s later. Both come at once when "Plan" is pressed or
:func:`wait_ready` is called, and after :data:`START_ANYWAY_S` when no page opens.
"Plan" pressed while the planner loads says so and plans when it is ready. A plan: the goals of the end effectors the
chosen group moves -> IK and the pipeline (one :class:`~maru_planner.planning.types.MotionRequest`) -> the trajectory
played by :class:`~maru_planner.web.plan_view.PlanView`, whose final state becomes the next start.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections.abc import Sequence

import numpy as np
import viser

from maru_planner import errors
from maru_planner.collision.checker import CollisionChecker
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStatus, set_failure
from maru_planner.robot import RobotModel
from maru_planner.robot.attached import check_attachments
from maru_planner.runtime import PlanningRuntime, RobotSource, RuntimeSettings, SceneEdit
from maru_planner.runtime.scene_store import load_scene_dict
from maru_planner.scene import Scene
from maru_planner.web.plan_view import PlanView
from maru_planner.web.planning_panel import PlanningPanel, default_group
from maru_planner.web.scene_edit import SceneEditor
from maru_planner.web.serving import DEFAULT_HOST, serve

_LOG = logging.getLogger(__name__)
PAGE_SETTLE_S = 1.0  # s after the first page's camera report: its first frame is drawn meanwhile
START_ANYWAY_S = 10.0  # s: the planner loads this long after start even when no page opened
PLAN_WAIT_S = 900.0  # s a press waits for a loading planner (a robot's first sphere fit can take minutes)
PLAN_LABEL, LOADING_LABEL = "Plan", "Plan (the planner is loading)"


@dataclasses.dataclass(frozen=True)
class ViewSettings:
    """Where ``maru-view`` serves (port 0: a free one) and what it loads."""

    robot: str = "maru1"
    scene: str = ""  # a scene file as load_scene_dict takes it ("" the package's desk scene, "none" empty)
    host: str = DEFAULT_HOST
    port: int = 8080
    collision_model: str = PlannerConfig.collision_model  # "spheres" (a robot's first use fits its spheres) | "exact"


class ViewApp:
    """The interactive view of one robot (module doc). Construction raises a MaruError for a bad robot or scene."""

    def __init__(self, settings: ViewSettings, config: PlannerConfig | None = None):
        self.settings = settings
        self.source = RobotSource(profile=settings.robot)
        self.robot = self.source.load()  # the view's own model: its FK is not shared with the workers
        self._scene = Scene.from_dict(load_scene_dict(settings.scene))  # checked before the server starts
        check_attachments(self.robot, self._scene)
        self.config = config or PlannerConfig(collision_model=settings.collision_model)
        self.runtime: PlanningRuntime | None = None
        self.server = serve(settings.host, settings.port)
        self.server.gui.configure_theme(control_width="large")
        self.view = PlanView(self.server, self.robot, self.source)
        self.panel = PlanningPanel(self.server, self.robot, self.plan_async)
        self.editor = SceneEditor(self.server, self.robot, self.apply_edits, self.scene_dict, self.joint_values)
        self.start = rest_state(self.robot, self._scene)
        self.view.show_start(self.start)
        self.view.show_scene(self._scene)
        self.editor.refresh(self._scene.to_dict())
        self.panel.place_goals(self.start)
        self._show_controls(False)  # until the first page has drawn the robot (module doc)
        self.ready = threading.Event()
        self._wanted = threading.Event()  # build the runtime now (the page is up, or a plan waits for it)
        self._closed = False
        self.last_result: MotionResult | None = None
        self._plan_lock = threading.Lock()
        self.panel.plan_button.disabled = False
        self.panel.plan_button.label = LOADING_LABEL
        self.panel.message.content = "the planner loads once the page is shown; Plan waits for it"
        self.server.on_client_connect(self._on_client)
        threading.Thread(target=self._start_runtime, daemon=True, name="maru-view-runtime").start()

    @property
    def url(self) -> str:
        return f"http://{self.settings.host}:{self.server.get_port()}"

    def close(self) -> None:
        self._closed = True  # a runtime not built yet is not built now
        self._wanted.set()
        self.server.stop()
        self.ready.wait(timeout=60.0)
        if self.runtime is not None:
            self.runtime.shutdown()

    # ------------------------------------------------------------ planning
    def plan_async(self) -> None:
        """What "Plan" does: plan in a thread (a press while planning is ignored)."""
        threading.Thread(target=self.plan, daemon=True, name="maru-view-plan").start()

    def plan(self) -> MotionResult | None:
        """Plan from the shown start to the goals with the panel's choices and play the trajectory; None if busy."""
        if not self._plan_lock.acquire(blocking=False):
            return None
        try:
            self.panel.message.content = "planning ..."
            t0 = time.monotonic()
            result = self._plan_once()
            self.panel.message.content = f"{result.status.value} in {1e3 * (time.monotonic() - t0):.0f} ms"
            self.view.show_result(result, self.start)
            if result.success and result.trajectory is not None:
                self.start = self.view.state_at(result.trajectory.duration)
            self.last_result = result  # last: a waiter sees the result shown and playing
            return result
        finally:
            self._plan_lock.release()

    def _plan_once(self) -> MotionResult:
        result = MotionResult(PlanStatus.PLANNING_FAILED)
        try:
            runtime = self._runtime()
            self._configure(runtime)
            request = MotionRequest(
                group=self.panel.group.value,
                start=self.joint_values(),
                goal_poses=self.panel.goal_poses(),
                planner_id=self.panel.planner.value,
                time_budget=float(self.panel.budget.value),
            )
            return runtime.plan(request).result()
        except errors.MaruError as exc:
            set_failure(result, exc)
            return result

    def _configure(self, runtime: PlanningRuntime) -> None:
        """Serve with the panel's planner parameters (rebuilding the worker only when they changed)."""
        params = self.panel.planner_params()
        wanted = {self.panel.planner.value: params} if params else {}
        if runtime.config.planner_params != wanted:
            runtime.reconfigure(dataclasses.replace(runtime.config, planner_params=wanted), runtime.settings)

    def _runtime(self) -> PlanningRuntime:
        """The runtime, waiting while it loads; Busy if it is not ready within PLAN_WAIT_S or did not start."""
        if not self.ready.is_set():
            self._wanted.set()
            self.panel.message.content = "waiting for the planner to load, then planning ..."
        if not self.ready.wait(PLAN_WAIT_S):
            raise errors.Busy(f"the planner did not get ready within {PLAN_WAIT_S:g} s")
        if self.runtime is None:
            raise errors.Busy("the planner did not start (see the message above); restart maru-view")
        return self.runtime

    # ------------------------------------------------------------ scene
    def scene_dict(self) -> dict:
        return self.runtime.get_scene()[0] if self.runtime is not None else self._scene.to_dict()

    def apply_edits(self, edits: Sequence[SceneEdit]) -> None:
        """Apply ``edits`` to the planning scene (all or nothing) and redraw it."""
        self._runtime().apply_scene(edits)
        scene = self.scene_dict()
        self.view.show_scene(scene)
        self.editor.refresh(scene)

    def set_scene(self, scene: Scene) -> None:
        """Make ``scene`` the planning scene and show it (its attached objects checked against the robot)."""
        self._runtime().set_scene(scene)
        shown = self.scene_dict()
        self.view.show_scene(shown)
        self.editor.refresh(shown)

    def set_start(self, start: np.ndarray | dict[str, float]) -> None:
        """Plan from ``start`` (a configuration, or joint values by name) next; the goals go to its end effectors."""
        self.view.show_start(start)
        self.start = self.view.robot_view.q.copy()
        self.panel.place_goals(self.start)

    def joint_values(self) -> dict[str, float]:
        return dict(zip(self.robot.joint_names, np.asarray(self.start, dtype=float).tolist(), strict=True))

    # ------------------------------------------------------------ start-up
    def _note(self, line: str) -> None:
        """A start-up note of the runtime (a first sphere fit can take minutes): logged and shown in the panel."""
        _LOG.info(line)
        self.panel.message.content = f"loading the planner: {line}"

    def want_planner(self) -> None:
        """Load the planner now rather than after the first page is up."""
        self._wanted.set()

    def _on_client(self, client: viser.ClientHandle) -> None:
        """A page connected: show the controls and load the planner once its camera reports (its canvas is up) and
        its first frame is drawn: PAGE_SETTLE_S later, or as long again as the canvas took (a loaded machine draws
        slowly too)."""
        reported, connected = threading.Event(), time.monotonic()

        def on_camera(_: viser.CameraHandle) -> None:
            if not reported.is_set():
                reported.set()
                settle = max(PAGE_SETTLE_S, time.monotonic() - connected)
                timer = threading.Timer(settle, self._wanted.set)
                timer.daemon = True
                timer.start()

        client.camera.on_update(on_camera)

    def _show_controls(self, shown: bool) -> None:
        with self.server.atomic():
            self.view.folder.visible = shown
            self.panel.set_shown(shown)
            self.editor.folder.visible = shown

    def _start_runtime(self) -> None:
        self._wanted.wait(START_ANYWAY_S)
        if self._closed:
            self.ready.set()
            return
        self._show_controls(True)
        t0 = time.monotonic()
        try:
            settings = RuntimeSettings(default_group=default_group(self.robot), workers=1, worker_processes=False)
            self.runtime = PlanningRuntime(self.source, self._scene, self.config, settings, log=self._note)
        except errors.MaruError as exc:
            self.panel.message.content = f"**the planner did not start**: {exc.message}"
            self.panel.plan_button.disabled = True
            return
        finally:
            self.panel.plan_button.label = PLAN_LABEL
            self.ready.set()
        self.panel.message.content = f"planner ready ({time.monotonic() - t0:.1f} s)"


def rest_state(robot: RobotModel, scene: Scene) -> np.ndarray:
    """The first collision-free (self and ``scene``) of: the SRDF's "home", "ready", its other named states in order,
    the neutral configuration; the first of them when none is (Talos' neutral pose has its arms in its legs)."""
    names: list[str] = [n for n in ("home", "ready") if n in robot.named_states]
    names += [n for n in robot.named_states if n not in names]
    candidates = [robot.named_state(n) for n in names] + [robot.neutral()]
    checker = CollisionChecker(robot, scene)
    return next((q for q in candidates if checker.is_valid(q)), candidates[0])


def wait_ready(app: ViewApp, timeout: float) -> None:
    """Block until ``app``'s planner is ready (loading it now if it waits for a page); Busy after ``timeout`` s."""
    app.want_planner()
    if not app.ready.wait(timeout) or app.runtime is None:
        raise errors.Busy(f"the planner did not get ready within {timeout:g} s")
