"""Planning in worker processes: :class:`ProcessPool` (pure core, no ROS).

Every OMPL search of a process runs under one lock (OMPL's seed generator is process-global,
:mod:`~maru_planner.planning.motion_planner`), so planning threads queue; worker processes plan in
parallel. Each worker builds its own robot model and :class:`MotionPlanner` once, from picklable
inputs (:class:`RobotSource`, a scene dict, a :class:`PlannerConfig`), and plans the requests the pool
hands it, one at a time; the same seed gives the same path as planning in the caller's process.

* ``submit(request, monitor)`` returns a ``concurrent.futures.Future`` of the :class:`MotionResult`
  (a typed error stays in ``result.error`` with its class and message). With a ``monitor``, the
  worker's stages and progress are reported to it, and ``monitor.cancel()`` cancels the plan in the
  worker (its own :class:`PlanMonitor` is cancelled, which ends the OMPL search at once).
* ``set_scene`` / ``set_config`` reach every worker before its next request.
* Workers start from a fork server that has imported the planning modules once (fork would copy the
  caller's threads, e.g. rclpy's, in an undefined state), all at the same time and in the background:
  the constructor returns at once, :meth:`wait_ready` waits for them (requests submitted meanwhile wait too).
  A worker exits when the pool closes or its pipe to the caller breaks (the caller died); one that dies
  while the pool runs fails its request with :class:`~maru_planner.errors.PlanningFailed` and is replaced.

Messages on a worker's pipe: to the worker ``("plan", job, request, forward_progress)``,
``("cancel", job)``, ``("scene", scene_dict)``, ``("config", config)``, ``("stop",)``; from it
``("ready", warm_up_summary)``, ``("broken", message)``, ``("progress", job, stage, info)``,
``("result", job, result)``.
"""

from __future__ import annotations

import contextlib
import itertools
import multiprocessing
import os
import pickle
import queue
import signal
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from multiprocessing.context import ForkServerContext, SpawnContext
from typing import cast

from maru_planner import errors
from maru_planner.monitor import PlanMonitor, Progress
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.types import MotionRequest, MotionResult
from maru_planner.runtime.robot_loading import RobotSource
from maru_planner.runtime.warm_up import warm_up
from maru_planner.scene import Scene

START_METHOD = "forkserver"  # not "fork": the caller may run rclpy/DDS threads a fork would copy half-way
START_METHODS = ("forkserver", "spawn")
_ProcessContext = ForkServerContext | SpawnContext
STOP_TIMEOUT = 5.0  # s a stopping worker may take to finish (a cancelled plan ends within milliseconds)


# ---------------------------------------------------------------- worker process


class _Inbox:
    """The worker's reader thread: cancels at once, queues everything else for the planning thread.

    A plan's :class:`PlanMonitor` is made here, so a cancel that arrives before the plan starts still
    reaches it. EOF before a stop means the pool's process is gone: the worker exits at once.
    """

    def __init__(self, conn: Connection, send: Callable[[tuple], None]):
        self._conn = conn
        self._send = send
        self._messages: queue.SimpleQueue[tuple | None] = queue.SimpleQueue()
        self._monitors: dict[int, PlanMonitor] = {}
        self._lock = threading.Lock()
        threading.Thread(target=self._read, name="inbox", daemon=True).start()

    def next(self) -> tuple | None:
        """The next message for the planning thread; None once the worker must stop."""
        return self._messages.get()

    def done(self, job: int) -> None:
        with self._lock:
            self._monitors.pop(job, None)

    def _read(self) -> None:
        while True:
            try:
                message = self._conn.recv()
            except (EOFError, OSError):
                os._exit(0)  # the pool's process died: no one is left to answer
            kind = message[0]
            if kind == "cancel":
                self._cancel(message[1])
            elif kind == "plan":
                self._queue_plan(*message[1:])
            elif kind == "stop":
                self._stop()
                return
            else:
                self._messages.put(message)

    def _queue_plan(self, job: int, request: MotionRequest, forward_progress: bool) -> None:
        monitor = PlanMonitor(self._progress_sender(job) if forward_progress else None)
        with self._lock:
            self._monitors[job] = monitor
        self._messages.put(("plan", job, request, monitor))

    def _progress_sender(self, job: int) -> Callable[[Progress], None]:
        def forward(progress: Progress) -> None:
            self._send(("progress", job, progress.stage, progress.info))

        return forward

    def _cancel(self, job: int) -> None:
        with self._lock:
            monitor = self._monitors.get(job)
        if monitor is not None:
            monitor.cancel()

    def _stop(self) -> None:
        with self._lock:
            monitors = list(self._monitors.values())
        for monitor in monitors:
            monitor.cancel()
        self._messages.put(None)


def _worker_main(conn: Connection, robot: RobotSource, scene: dict, config: PlannerConfig) -> None:
    """A worker process: build the planner once, then plan until told to stop."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group; the pool stops us
    send_lock = threading.Lock()

    def send(message: tuple) -> None:
        with send_lock:
            conn.send(message)

    inbox = _Inbox(conn, send)  # reading already: the pool never blocks on a pipe a building worker leaves full
    try:
        model = robot.load()
        planner = MotionPlanner.from_scene(model, Scene.from_dict(scene), config)
    except Exception as exc:  # noqa: BLE001 - reported to the pool, which refuses to start
        send(("broken", errors.one_line(f"{type(exc).__name__}: {exc}")))
        return
    warmed = warm_up(model, config)  # no request pays numba's compile or cache load (its module doc)
    send(("ready", warmed.summary()))
    while (message := inbox.next()) is not None:
        kind = message[0]
        if kind == "scene":
            planner.set_scene(Scene.from_dict(message[1]))
        elif kind == "config":
            planner = MotionPlanner.from_scene(model, planner.scene, message[1])
            warm_up(model, message[1])
        elif kind == "plan":
            _, job, request, monitor = message
            result = planner.plan(request, monitor)
            inbox.done(job)
            send(("result", job, _portable(result)))


def _portable(result: MotionResult) -> MotionResult:
    """``result`` with an error the pool's process can unpickle (else a RuntimeError with its message)."""
    if result.error is not None:
        try:
            pickle.loads(pickle.dumps(result.error))
        except Exception:  # noqa: BLE001 - any exception a third-party library raised
            result.error = RuntimeError(result.message)
    return result


# ---------------------------------------------------------------- the pool (caller's process)


@dataclass
class _Job:
    job_id: int
    request: MotionRequest
    monitor: PlanMonitor | None
    future: Future
    attached: contextlib.ExitStack = field(default_factory=contextlib.ExitStack)
    lock: threading.Lock = field(default_factory=threading.Lock)  # the monitor is attached before it is detached

    def detach(self) -> None:
        with self.lock:
            self.attached.close()


class _Worker:
    """The pool's handle on one worker process: its pipe, the job it plans, its state."""

    def __init__(self, process, conn: Connection):
        self.process = process
        self.conn = conn
        self.job: _Job | None = None
        self.ready = threading.Event()
        self.failure = ""  # why it could not start
        self.warm_up = ""  # its kernel warm-up, one line (warm_up.WarmUp.summary)
        self.retiring = False
        self.reader: threading.Thread | None = None
        self._send_lock = threading.Lock()

    def send(self, message: tuple) -> None:
        """Send ``message``; nothing if the worker is gone (its reader thread handles that)."""
        with contextlib.suppress(OSError, ValueError), self._send_lock:
            self.conn.send(message)


class _CancelInWorker:
    """Attached to a request's monitor while its worker plans it: ``cancel()`` reaches the worker."""

    def __init__(self, worker: _Worker, job_id: int):
        self.worker = worker
        self.job_id = job_id

    def terminate(self) -> None:
        self.worker.send(("cancel", self.job_id))


class ProcessPool:
    """Planning worker processes with one request each at a time and a queue in front (module doc)."""

    def __init__(
        self,
        robot: RobotSource,
        scene: dict,
        config: PlannerConfig | None = None,
        workers: int = 2,
        start_method: str = START_METHOD,
        scene_version: int = 0,
    ):
        """``workers`` processes planning on ``scene`` (version ``scene_version``) with ``config``.

        ``start_method`` "forkserver" or "spawn" (never "fork"); InvalidParameter for anything else.
        """
        if workers < 1:
            raise errors.InvalidParameter(f"workers must be >= 1, got {workers}")
        if start_method not in START_METHODS:
            raise errors.InvalidParameter(f"start_method must be one of {START_METHODS}, got {start_method!r}")
        self._mp = cast(_ProcessContext, multiprocessing.get_context(start_method))
        if start_method == "forkserver":
            self._mp.set_forkserver_preload([__name__])  # the fork server imports the planning stack once
        self._robot = robot
        self._scene, self._scene_version = scene, scene_version
        self._config = config or PlannerConfig()
        self._lock = threading.Lock()
        self._workers: list[_Worker] = []
        self._idle: list[_Worker] = []
        self._pending: deque[_Job] = deque()
        self._job_ids = itertools.count()
        self._worker_ids = itertools.count()
        self._closed = False
        self._start_failure = ""
        # the constructor returns at once: the caller builds what it needs while the fork server imports
        self._starting = threading.Thread(target=self._start_first, args=(workers,), name="maru-planner-start")
        self._starting.start()

    # --- life cycle ----------------------------------------------------------------------
    @property
    def workers(self) -> int:
        """Worker processes planning or waiting for a request (not counting retiring ones)."""
        with self._lock:
            return sum(not w.retiring for w in self._workers)

    @property
    def scene_version(self) -> int:
        """The version of the scene the workers plan on (:meth:`set_scene`)."""
        return self._scene_version

    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def pids(self) -> list[int]:
        with self._lock:
            return [w.process.pid for w in self._workers]

    def wait_ready(self, timeout: float = 300.0) -> None:
        """Block until every worker has built its planner; a worker that could not is a MaruError."""
        deadline = time.monotonic() + timeout
        self._starting.join(timeout)
        if self._start_failure:
            self.close()
            raise errors.MaruError(f"planning workers failed to start: {self._start_failure}", source="workers")
        with self._lock:
            workers = list(self._workers)
        for worker in workers:
            if not worker.ready.wait(max(0.0, deadline - time.monotonic())):
                self.close()
                raise errors.MaruError(f"planning worker {worker.process.name} not ready within {timeout} s")
        failures = [w.failure for w in workers if w.failure]
        if failures:
            self.close()
            raise errors.MaruError(f"planning worker failed to start: {failures[0]}", source="workers")

    def warm_ups(self) -> list[str]:
        """Each ready worker's kernel warm-up, one line (``warm_up.WarmUp.summary``)."""
        with self._lock:
            return [w.warm_up for w in self._workers if w.ready.is_set() and not w.failure]

    def resize(self, workers: int) -> None:
        """Start or retire workers until ``workers`` plan (a retiring one finishes its request first)."""
        if workers < 1:
            raise errors.InvalidParameter(f"workers must be >= 1, got {workers}")
        self._starting.join()
        with self._lock:
            active = [w for w in self._workers if not w.retiring]
            retire = active[workers:]
            for worker in retire:
                worker.retiring = True
            idle = [w for w in retire if w in self._idle]
            self._idle = [w for w in self._idle if w not in idle]
        for worker in idle:
            worker.send(("stop",))
        self._start_workers(workers - len(active))

    def close(self) -> None:
        """Stop every worker: waiting requests fail with PlanningCancelled, running ones are cancelled."""
        self._starting.join()
        with self._lock:
            self._closed = True
            pending, self._pending = list(self._pending), deque()
            workers = list(self._workers)
        for job in pending:
            if job.future.set_running_or_notify_cancel():
                job.future.set_exception(errors.PlanningCancelled("the planning workers stopped", source="workers"))
        for worker in workers:
            worker.send(("stop",))
        for worker in workers:
            _reap(worker.process)
            if worker.reader is not None:  # it delivers the cancelled results still in the pipe
                worker.reader.join(STOP_TIMEOUT)

    def __enter__(self) -> ProcessPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- requests and updates --------------------------------------------------------------
    def submit(self, request: MotionRequest, monitor: PlanMonitor | None = None) -> Future:
        """Plan ``request`` in the next free worker: a Future of its MotionResult (module doc)."""
        job = _Job(next(self._job_ids), request, monitor, Future())
        with self._lock:
            if self._closed:
                raise RuntimeError("the process pool is closed")
            worker = self._idle.pop() if self._idle else None
            if worker is None:
                self._pending.append(job)
            else:
                worker.job = job
        if worker is not None:
            self._start(worker, job)
        return job.future

    def plan(self, request: MotionRequest, monitor: PlanMonitor | None = None) -> MotionResult:
        """``submit(request, monitor).result()``: like :meth:`MotionPlanner.plan`, in a worker."""
        return self.submit(request, monitor).result()

    def set_scene(self, scene: dict, version: int) -> None:
        """Every worker plans on ``scene`` (a :meth:`Scene.to_dict`) from its next request on.

        ``version`` numbers the scenes: one not newer than :attr:`scene_version` is ignored (several
        threads may pass on the same change). InvalidScene (no worker touched) if ``scene`` is malformed.
        """
        if version <= self._scene_version:
            return
        Scene.from_dict(scene)
        with self._lock:
            if version <= self._scene_version:
                return
            self._scene, self._scene_version = scene, version
            self._broadcast(("scene", scene))

    def set_config(self, config: PlannerConfig) -> None:
        """Every worker plans with ``config`` from its next request on."""
        with self._lock:
            self._config = config
            self._broadcast(("config", config))

    def _broadcast(self, message: tuple) -> None:
        """Send ``message`` to every worker (under the pool's lock: one started meanwhile gets the new value)."""
        for worker in self._workers:
            worker.send(message)

    # --- dispatch (callers' threads and the readers) ----------------------------------------
    def _start_first(self, count: int) -> None:
        try:
            self._start_workers(count)
        except Exception as exc:  # noqa: BLE001 - wait_ready reports it (e.g. no fork server: OSError)
            self._start_failure = errors.one_line(f"{type(exc).__name__}: {exc}")

    def _start_workers(self, count: int) -> None:
        for _ in range(max(0, count)):
            parent_end, child_end = self._mp.Pipe()
            with self._lock:
                process = self._mp.Process(
                    target=_worker_main,
                    args=(child_end, self._robot, self._scene, self._config),
                    name=f"maru-planner-worker-{next(self._worker_ids)}",
                    daemon=True,
                )
                process.start()
                worker = _Worker(process, parent_end)
                self._workers.append(worker)
            child_end.close()
            worker.reader = threading.Thread(target=self._read, args=(worker,), name=process.name, daemon=True)
            worker.reader.start()

    def _start(self, worker: _Worker, job: _Job) -> None:
        """Send ``job`` to ``worker`` (its monitor's cancel now reaches the worker)."""
        if not job.future.set_running_or_notify_cancel():  # the caller cancelled the Future meanwhile
            self._next_job(worker)
            return
        with job.lock:
            worker.send(("plan", job.job_id, job.request, job.monitor is not None))
            if job.monitor is not None:  # after the plan: a monitor cancelled already sends its cancel at once
                job.attached.enter_context(job.monitor.attach(_CancelInWorker(worker, job.job_id)))

    def _next_job(self, worker: _Worker) -> None:
        """Give ``worker`` the next waiting job, else mark it idle (a retiring one stops instead)."""
        with self._lock:
            job = None
            if not worker.retiring and not self._closed:
                job = self._pending.popleft() if self._pending else None
                if job is None:
                    self._idle.append(worker)
            worker.job = job
        if job is not None:
            self._start(worker, job)
        elif worker.retiring:
            worker.send(("stop",))

    def _read(self, worker: _Worker) -> None:
        """Reader thread of one worker: readiness, progress and results, until its pipe closes."""
        while True:
            try:
                message = worker.conn.recv()
            except (EOFError, OSError):
                self._lost(worker)
                return
            kind = message[0]
            if kind == "ready":
                worker.warm_up = message[1]
                worker.ready.set()
                self._next_job(worker)
            elif kind == "broken":
                worker.failure = message[1]
                worker.ready.set()
            elif kind == "progress":
                self._forward_progress(worker, *message[1:])
            elif kind == "result":
                self._finish(worker, message[1], message[2])

    def _forward_progress(self, worker: _Worker, job_id: int, stage: str, info: dict) -> None:
        job = worker.job
        if job is None or job.job_id != job_id or job.monitor is None:
            return
        with contextlib.suppress(errors.PlanningCancelled):  # the worker reports the cancel in its result
            job.monitor.report(stage, **info)

    def _finish(self, worker: _Worker, job_id: int, result: MotionResult) -> None:
        job = worker.job
        if job is None or job.job_id != job_id:
            return
        job.detach()
        job.future.set_result(result)
        self._next_job(worker)

    def _lost(self, worker: _Worker) -> None:
        """The worker's pipe closed: it stopped, or died (then its job fails and a new worker replaces it)."""
        with self._lock:
            if worker in self._workers:
                self._workers.remove(worker)
            if worker in self._idle:
                self._idle.remove(worker)
            job, worker.job = worker.job, None
            if not worker.ready.is_set():  # died while building its planner: wait_ready reports it, no restart loop
                worker.failure = worker.failure or f"{worker.process.name} exited before it was ready"
                worker.ready.set()
            replace = not (self._closed or worker.retiring or worker.failure)
        worker.conn.close()
        _reap(worker.process)
        if job is not None:
            job.detach()
            job.future.set_exception(
                errors.PlanningFailed(
                    f"planning worker {worker.process.name} exited (code {worker.process.exitcode}) while planning",
                    source="workers",
                )
            )
        if replace:
            self._start_workers(1)


def _reap(process) -> None:
    """Join ``process``; terminate, then kill it if it does not end within :data:`STOP_TIMEOUT`."""
    process.join(STOP_TIMEOUT)
    if process.is_alive():
        process.terminate()
        process.join(1.0)
    if process.is_alive():
        process.kill()
        process.join()
