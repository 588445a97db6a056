"""The planning service without ROS: :class:`PlanningRuntime`, what ``planning_node`` calls (MoveIt's
``move_group`` context is the model).

It owns the robot (loaded from a :class:`~maru_planner.runtime.robot_loading.RobotSource`), the versioned scene
(:class:`~maru_planner.runtime.scene_store.SceneStore`), the robot's latest joint values
(:class:`~maru_planner.runtime.robot_state.JointStateStore`) and the workers. Every request runs on a
:class:`~maru_planner.runtime.admission.WorkerPool` of ``workers`` threads, each owning its own robot model,
collision checker and planner (pinocchio data and OMPL set-ups are not shared between threads); a request
method returns a ``concurrent.futures.Future`` at once, or raises ``errors.Busy`` when its expected wait exceeds
its budget or ``workers + queue_size`` requests are already planning or waiting (:mod:`admission`). Time spent
waiting counts against the request's own budget; a plan cancelled (its monitor) while it waits ends at once.
With ``worker_processes`` each thread hands its plan to one of ``workers`` worker processes
(:class:`~maru_planner.runtime.process_pool.ProcessPool`: own OMPL, model and scene, brought to the runtime's
scene before the next plan), so concurrent plans run on every core; threads alone take turns in OMPL (one
process-wide lock). Before it answers its first request, every planner has run its kernels once
(:mod:`~maru_planner.runtime.warm_up`).
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Future, wait
from dataclasses import dataclass
from typing import Any

import numpy as np

from maru_planner import errors, heap
from maru_planner.collision import sphere_model
from maru_planner.monitor import PlanMonitor
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.constraints import PathConstraints
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.queries import StateValidity
from maru_planner.planning.types import MotionRequest, MotionResult
from maru_planner.robot import RobotModel
from maru_planner.runtime import requests
from maru_planner.runtime.admission import WorkerContext, WorkerPool
from maru_planner.runtime.process_pool import ProcessPool
from maru_planner.runtime.requests import IkRequest
from maru_planner.runtime.robot_loading import RobotSource, check_group
from maru_planner.runtime.robot_state import JointStateStore
from maru_planner.runtime.scene_store import Attachments, SceneEdit, SceneStore, load_scene_dict
from maru_planner.runtime.warm_up import warm_up
from maru_planner.scene import Scene

_LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class RuntimeSettings:
    """How the runtime serves: the default planning group (checked against the robot), the workers, admission."""

    default_group: str = "upper_body"
    workers: int = 2
    worker_processes: bool = True
    queue_size: int = 200


class PlanningRuntime:
    """Robot, scene, joint state and workers of the planning service; thread-safe (module doc)."""

    def __init__(
        self,
        source: RobotSource,
        scene: Scene | str = "",
        config: PlannerConfig | None = None,
        settings: RuntimeSettings | None = None,
        *,
        log: Callable[[str], None] = _LOG.info,
        joint_states: JointStateStore | None = None,
    ):
        """Load the robot, check ``settings.default_group``, load the scene (a :class:`Scene`, or a scene file as
        :func:`~maru_planner.runtime.scene_store.load_scene_dict` takes it), start the workers and warm them up.

        ``log`` gets the one-line notes of the start-up (sphere fit, warm-ups); ``joint_states`` is the store of
        the robot's latest joint values (kept by the caller across runtimes; default: a new one).
        """
        self.source = source
        self.robot = source.load()  # read-only use by callers (names, markers); each worker loads its own
        self.joint_names = frozenset(self.robot.joint_names)
        self.config, self.settings = config or PlannerConfig(), settings or RuntimeSettings()
        check_group(self.robot, self.settings.default_group)
        self._scenes = SceneStore(scene.to_dict() if isinstance(scene, Scene) else load_scene_dict(scene))
        self._joint_states = joint_states if joint_states is not None else JointStateStore()
        self._attachments = Attachments(self.robot, self._joint_states.latest)
        self._log = log
        self._lock = threading.Lock()
        self._processes: ProcessPool | None = None  # worker_processes: kept (reconfigured) across pool rebuilds
        try:
            self._pool = self._make_pool(self.config, self.settings)
        except BaseException:
            if self._processes is not None:
                self._processes.close()
            raise

    def __enter__(self) -> PlanningRuntime:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()

    # ------------------------------------------------------------ requests (Futures; errors.Busy when full)

    def plan(self, request: MotionRequest, monitor: PlanMonitor | None = None) -> Future[MotionResult]:
        """Plan ``request`` within its ``time_budget`` from now (``monitor``: progress and cancel)."""
        deadline = time.monotonic() + request.time_budget
        waiting = self._enqueue(requests.plan_in_context, request, deadline, monitor, budget=request.time_budget)
        if monitor is not None:  # a cancel while it waits for a worker ends it now, not when a worker takes it
            hook = contextlib.ExitStack()
            hook.enter_context(monitor.attach(waiting))
            waiting.future.add_done_callback(lambda _done: hook.close())
        return waiting.future

    def cartesian_path(self, request: CartesianRequest) -> Future[CartesianResult]:
        return self._submit(requests.cartesian_in_context, request)

    def compute_ik(self, request: IkRequest) -> Future[np.ndarray]:
        """A full configuration solving ``request`` within its ``timeout`` from now."""
        deadline = time.monotonic() + request.timeout
        return self._submit(requests.ik_in_context, request, deadline, budget=request.timeout)

    def compute_fk(self, values: dict[str, float], links: Sequence[str]) -> Future[dict[str, np.ndarray]]:
        """{link: 4x4 pose} at joint ``values`` (every name a robot joint); every link when ``links`` is empty."""
        return self._submit(requests.fk_in_context, values, list(links))

    def check_state_validity(self, values: dict[str, float], constraints: PathConstraints) -> Future[StateValidity]:
        return self._submit(requests.validity_in_context, values, constraints)

    # ------------------------------------------------------------ scene

    def get_scene(self) -> tuple[dict, int]:
        """(a copy of the scene as :meth:`Scene.to_dict`, its version)."""
        return self._scenes.snapshot()

    @property
    def scene_version(self) -> int:
        return self._scenes.version

    def obstacle_names(self) -> list[str]:
        return self._scenes.obstacle_names()

    def apply_scene(self, edits: Iterable[SceneEdit], clear: bool = False) -> list[str]:
        """Apply ``edits`` all-or-nothing (:meth:`SceneStore.apply`); the obstacle names after them."""
        return self._scenes.apply(edits, clear, self._attachments)

    def set_scene(self, scene: Scene) -> int:
        """Make ``scene`` the scene (its attached objects checked against the robot); its version."""
        return self._scenes.replace(scene.to_dict(), self._attachments)

    # ------------------------------------------------------------ robot state

    @property
    def joint_states(self) -> JointStateStore:
        return self._joint_states

    def update_joint_state(self, names: Sequence[str], positions: Sequence[float]) -> int:
        """Store the robot's finite joint values among ``names``; the number of values ignored."""
        return self._joint_states.merge(names, positions, self.joint_names)

    def latest_joint_state(self) -> dict[str, float]:
        return self._joint_states.latest()

    # ------------------------------------------------------------ workers

    @property
    def workers(self) -> int:
        with self._lock:
            return self._pool.workers

    @property
    def worker_pids(self) -> list[int]:
        """The process ids of the worker processes (none without ``worker_processes``); one killed is replaced."""
        processes = self._processes
        return processes.pids if processes is not None else []

    @property
    def admitted(self) -> int:
        """Requests planning or waiting for a worker."""
        with self._lock:
            return self._pool.admitted

    def reconfigure(self, config: PlannerConfig, settings: RuntimeSettings) -> bool:
        """Serve with ``config`` and ``settings`` from the next request on; whether the workers were rebuilt.

        A planner setting or ``workers`` builds a new worker pool first (raising leaves everything as it was);
        requests already admitted finish on the old one. ``worker_processes`` is fixed at construction.
        """
        check_group(self.robot, settings.default_group)
        rebuild = config != self.config or settings.workers != self.settings.workers
        pool = self._make_pool(config, settings) if rebuild else None
        with self._lock:
            self.settings, self.config = settings, config
            if pool is not None:
                self._pool, old = pool, self._pool
                old.close()
            self._pool.queue_size = settings.queue_size
        return rebuild

    def shutdown(self) -> None:
        """Stop the workers (admitted requests finish, waiting plans in worker processes are cancelled) and forget
        the joint values."""
        with self._lock:
            self._pool.close()
            if self._processes is not None:
                self._processes.close()
        self._joint_states.clear()

    # ------------------------------------------------------------ inside

    def _submit(self, fn: Callable[..., Any], *args: Any, budget: float | None = None) -> Future:
        """Run ``fn(context, *args)`` on a planning worker, the context brought to the latest scene first
        (``budget``: the request's seconds, for admission)."""
        return self._enqueue(fn, *args, budget=budget).future

    def _enqueue(self, fn: Callable[..., Any], *args: Any, budget: float | None = None) -> _Waiting:
        waiting = _Waiting()

        def job(context: WorkerContext) -> bool:
            """Whether its run time tells the next request's (not when cancelled)."""
            if not waiting.start():
                return False
            try:
                self._sync_scene(context)
                result = fn(context, *args)
            except BaseException as exc:  # noqa: BLE001 - handed to whoever waits for the Future
                waiting.future.set_exception(exc)
                return not isinstance(exc, errors.PlanningCancelled)
            if isinstance(result, Future):  # a worker process plans it: the pool's reader thread answers the caller
                result.add_done_callback(waiting.forward)
                wait([result])  # this thread stays taken meanwhile (admission counts it)
                if result.cancelled():
                    return False
                if (error := result.exception()) is not None:
                    return not isinstance(error, errors.PlanningCancelled)
                result = result.result()
            else:
                waiting.future.set_result(result)
            return not isinstance(getattr(result, "error", None), errors.PlanningCancelled)

        with self._lock:
            self._pool.submit(job, budget)
        return waiting

    def _sync_scene(self, context: WorkerContext) -> None:
        """Bring the context's planner (and the worker processes) to the latest scene."""
        processes = context.processes
        latest = self._scenes.version
        if context.scene_version == latest and (processes is None or processes.scene_version >= latest):
            return
        scene_dict, version = self._scenes.snapshot()
        if context.scene_version != version:
            context.planner.set_scene(Scene.from_dict(scene_dict))
            context.scene_version = version
        if processes is not None:
            processes.set_scene(scene_dict, version)

    def _make_pool(self, config: PlannerConfig, settings: RuntimeSettings) -> WorkerPool:
        if config.collision_model == "spheres":
            self._fit_spheres_once()
        processes = self._reconfigured_processes(config, settings)
        contexts = [self._make_context(config, processes) for _ in range(settings.workers)]
        if processes is not None:
            processes.wait_ready()  # the workers build their planners and warm up meanwhile, in parallel
            for n, summary in enumerate(processes.warm_ups()):
                self._log(f"worker process {n}: {summary}")
        else:  # no request pays numba's compile or cache load (warm_up module doc)
            self._log(warm_up(contexts[0].planner.robot, config).summary())
        heap.release_free_memory()  # what building the planners freed (heap module doc)
        return WorkerPool(contexts, settings.queue_size)

    def _make_context(self, config: PlannerConfig, processes: ProcessPool | None) -> WorkerContext:
        scene_dict, version = self._scenes.snapshot()
        planner = MotionPlanner.from_scene(self.source.load(), Scene.from_dict(scene_dict), config)
        return WorkerContext(planner, version, processes)

    def _fit_spheres_once(self) -> None:
        """Fit the robot's sphere model here, once per geometry (disk-cached), so the planners and worker processes
        built next load it instead of each fitting it at the same time."""
        robot: RobotModel = self.robot
        notice = sphere_model.first_fit_notice(robot.name, robot.collision_model, robot.sphere_options)
        if notice:
            self._log(notice)
        sphere_model.load_or_fit(robot.model, robot.collision_model, robot.sphere_options)

    def _reconfigured_processes(self, config: PlannerConfig, settings: RuntimeSettings) -> ProcessPool | None:
        """The worker processes (``worker_processes``), started once, then given ``config`` and ``workers``."""
        if not settings.worker_processes:
            return None
        if self._processes is None or self._processes.closed:
            scene_dict, version = self._scenes.snapshot()
            self._processes = ProcessPool(self.source, scene_dict, config, settings.workers, scene_version=version)
        else:
            self._processes.set_config(config)
            self._processes.resize(settings.workers)
        return self._processes


class _Waiting:
    """A request's Future while it waits for a worker; a :class:`~maru_planner.monitor.Terminable` that ends it
    with PlanningCancelled at once (a running plan is stopped by its planner's own hook instead)."""

    def __init__(self) -> None:
        self.future: Future = Future()
        self._lock = threading.Lock()

    def start(self) -> bool:
        """A worker takes the request: whether it still waits (not cancelled meanwhile)."""
        with self._lock:
            return not self.future.done() and self.future.set_running_or_notify_cancel()

    def terminate(self) -> None:
        with self._lock:
            if not self.future.running() and not self.future.done():
                self.future.set_exception(errors.PlanningCancelled("cancelled while waiting for a worker"))

    def forward(self, done: Future) -> None:
        """End the request as ``done`` (a worker process's Future) ended."""
        if done.cancelled():
            self.future.set_exception(errors.PlanningCancelled("the planning workers stopped"))
        elif (error := done.exception()) is not None:
            self.future.set_exception(error)
        else:
            self.future.set_result(done.result())
