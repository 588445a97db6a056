"""Planning in worker processes: :class:`ProcessPool` (pure core, no ROS).

Every OMPL search of a process runs under one lock (OMPL's seed generator is process-global,
:mod:`~maru_planner.planning.motion_planner`), so planning threads queue; worker processes plan in
parallel. Each worker builds its own robot model and :class:`MotionPlanner` once, from picklable
inputs (:class:`RobotSource`, a scene dict, a :class:`PlannerConfig`), and plans the requests the pool
hands it, one at a time (:mod:`~maru_planner.runtime.worker_process`); the same seed gives the same path as
planning in the caller's process.

* ``submit(request, monitor)`` returns a ``concurrent.futures.Future`` of the :class:`MotionResult`
  (a typed error stays in ``result.error`` with its class and message). With a ``monitor``, the
  worker's stages and progress are reported to it, and ``monitor.cancel()`` cancels the plan in the
  worker (its own :class:`PlanMonitor` is cancelled, which ends the OMPL search at once).
* ``set_scene`` / ``set_config`` reach every worker before its next request.
* Workers start from a fork server that has imported the planning modules once (fork would copy the
  caller's threads, e.g. rclpy's, in an undefined state), all at the same time and in the background:
  the constructor returns at once, :meth:`wait_ready` waits for them (requests submitted meanwhile wait too).
  A worker exits when the pool closes or its pipe to the caller breaks (the caller died).
* A worker that dies while the pool runs (killed, out of memory, a crash in native code) fails its request at
  once with :class:`~maru_planner.errors.PlanningFailed` ("the planning worker 1234 died (signal 9, SIGKILL)
  while planning; it was restarted") and a new worker replaces it; requests waiting meanwhile are served by the
  other workers or the new one, their wait counted against their ``time_budget`` (PlanningTimedOut when it ran
  out). Only a worker that cannot start (its replacement included) is not restarted: with no worker left, what
  waits and what comes fails with PlanningFailed instead of waiting for ever.

Messages on a worker's pipe: to the worker ``("plan", job, request, forward_progress)``,
``("cancel", job)``, ``("scene", scene_dict)``, ``("config", config)``, ``("stop",)``; from it
``("ready", warm_up_summary)``, ``("broken", message)``, ``("progress", job, stage, info)``,
``("result", job, result)``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import logging
import multiprocessing
import signal
import threading
import time
from collections import deque
from concurrent.futures import Future
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from multiprocessing.context import ForkServerContext, SpawnContext
from typing import cast

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.types import MotionRequest, MotionResult
from maru_planner.runtime.robot_loading import RobotSource
from maru_planner.runtime.worker_process import worker_main
from maru_planner.scene import Scene

START_METHOD = "forkserver"  # not "fork": the caller may run rclpy/DDS threads a fork would copy half-way
START_METHODS = ("forkserver", "spawn")
_ProcessContext = ForkServerContext | SpawnContext
STOP_TIMEOUT = 5.0  # s a stopping worker may take to finish (a cancelled plan ends within milliseconds)
_LOG = logging.getLogger(__name__)


@dataclass
class _Job:
    job_id: int
    request: MotionRequest
    monitor: PlanMonitor | None
    future: Future
    submitted: float = field(default_factory=time.monotonic)
    queued: bool = False  # it waited for a worker: the wait counts against its time_budget
    attached: contextlib.ExitStack = field(default_factory=contextlib.ExitStack)
    lock: threading.Lock = field(default_factory=threading.Lock)  # starts, detaches and fails it one at a time

    def detach(self) -> None:
        with self.lock:
            self.attached.close()

    def fail(self, error: Exception) -> None:
        """Detach the monitor and end the Future with ``error`` (nothing if it has ended already)."""
        with self.lock:
            self.attached.close()
            if not self.future.done():
                self.future.set_exception(error)

    def request_left(self) -> MotionRequest | None:
        """The request with the time left of its budget after its wait; None once the wait used it up."""
        if not self.queued:
            return self.request
        left = self.request.time_budget - (time.monotonic() - self.submitted)
        return dataclasses.replace(self.request, time_budget=left) if left > 0.0 else None


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
        self._last_loss = ""  # why the last worker went: the error when none is left
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
            unserved = self._no_worker_left()
            worker = self._idle.pop() if self._idle and not unserved else None
            if worker is None and not unserved:
                job.queued = True
                self._pending.append(job)
            elif worker is not None:
                worker.job = job
        if unserved:
            job.fail(errors.PlanningFailed(unserved, source="workers"))
        elif worker is not None:
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
            with self._lock:
                if self._closed:  # close() has taken its list of workers: one started now would outlive the pool
                    return
                self._spawn()

    def _spawn(self) -> _Worker:
        """Start one worker process and its reader thread (the caller holds the pool's lock)."""
        parent_end, child_end = self._mp.Pipe()
        process = self._mp.Process(
            target=worker_main,
            args=(child_end, self._robot, self._scene, self._config),
            name=f"maru-planner-worker-{next(self._worker_ids)}",
            daemon=True,
        )
        try:
            process.start()
        except BaseException:
            parent_end.close()
            raise
        finally:
            child_end.close()
        worker = _Worker(process, parent_end)
        self._workers.append(worker)
        worker.reader = threading.Thread(target=self._read, args=(worker,), name=process.name, daemon=True)
        worker.reader.start()
        return worker

    def _no_worker_left(self) -> str:
        """Why no request can be served (no worker runs or starts), else "" (the caller holds the lock)."""
        if self._starting.is_alive() or any(not w.retiring for w in self._workers):
            return ""
        return f"no planning worker is running ({self._last_loss or self._start_failure or 'none started'})"

    def _start(self, worker: _Worker, job: _Job) -> None:
        """Send ``job`` to ``worker`` (its monitor's cancel now reaches the worker)."""
        if _gone(worker):  # died while idle, its reader not yet run: the job waits for another worker instead
            with self._lock:
                if worker.job is job:  # else the reader took it already, and fails it
                    worker.job = None
                    job.queued = True
                    self._pending.appendleft(job)
            return
        with job.lock:
            if job.future.done() and not job.future.cancelled():
                return  # the worker died before the plan went out: its reader failed the job
            running = job.future.set_running_or_notify_cancel()  # False: the caller cancelled the Future
            request = job.request_left() if running else None
            if request is not None:
                worker.send(("plan", job.job_id, request, job.monitor is not None))
                if job.monitor is not None:  # after the plan: a monitor cancelled already sends its cancel at once
                    job.attached.enter_context(job.monitor.attach(_CancelInWorker(worker, job.job_id)))
                return
            if running:
                job.future.set_exception(
                    errors.PlanningTimedOut("the time budget ran out while the request waited for a planning worker")
                )
        self._next_job(worker)

    def _next_job(self, worker: _Worker) -> None:
        """Give ``worker`` the next waiting job, else mark it idle (a retiring one stops instead)."""
        with self._lock:
            job = None
            if not worker.retiring and not self._closed and worker in self._workers:  # not one that died meanwhile
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
        worker.conn.close()
        _reap(worker.process)  # its exit code; at once for a process that is gone
        with self._lock:
            if worker in self._workers:
                self._workers.remove(worker)
            if worker in self._idle:
                self._idle.remove(worker)
            job, worker.job = worker.job, None
            if not worker.ready.is_set():  # died while building its planner: wait_ready reports it, no restart loop
                worker.failure = worker.failure or f"{worker.process.name} exited before it was ready"
                worker.ready.set()
            stopped = (self._closed or worker.retiring) and job is None  # told to stop: not a loss
            loss = "" if stopped else self._replace(worker, planning=job is not None)
            orphans, unserved = self._orphans()
        if loss:
            _LOG.warning(loss)
        if job is not None:
            job.fail(errors.PlanningFailed(loss, source="workers"))
        for orphan in orphans:
            orphan.fail(errors.PlanningFailed(unserved, source="workers"))

    def _replace(self, worker: _Worker, planning: bool) -> str:
        """Start a worker instead of the dead ``worker`` unless the pool is closing, ``worker`` was retiring or
        could not start; what happened, one line (the caller holds the lock)."""
        ending = f"the planning worker {worker.process.pid} {_exit_description(worker.process.exitcode)}"
        if worker.failure:
            outcome = f"it could not start: {worker.failure}"
        elif self._closed:
            outcome = "the pool is closing"
        elif worker.retiring:
            outcome = "it was retiring (not replaced)"
        else:
            try:
                outcome = f"it was restarted (as {self._spawn().process.pid})"
            except Exception as exc:  # noqa: BLE001 - e.g. the fork server is gone: no worker left, and no hang
                outcome = errors.one_line(f"it could not be restarted: {type(exc).__name__}: {exc}")
        self._last_loss = f"{ending}{' while planning' if planning else ''}; {outcome}"
        return self._last_loss

    def _orphans(self) -> tuple[list[_Job], str]:
        """(the waiting jobs, why) taken from the queue when no worker is left to serve them (lock held)."""
        unserved = "" if self._closed else self._no_worker_left()
        if not unserved:
            return [], ""
        orphans, self._pending = list(self._pending), deque()
        return orphans, unserved


def _gone(worker: _Worker) -> bool:
    """Whether an idle ``worker``'s pipe is at its end: it sends nothing while idle, so anything readable is the
    EOF of a worker that died (its reader thread replaces it and fails nothing: it held no job)."""
    try:
        return worker.conn.poll()
    except (OSError, ValueError):  # closed by its reader already
        return True


def _exit_description(exitcode: int | None) -> str:
    """How a worker process ended, from its ``exitcode`` (negative: the signal that killed it)."""
    if exitcode is None:
        return "closed its pipe"
    if exitcode < 0:
        with contextlib.suppress(ValueError):
            return f"died (signal {-exitcode}, {signal.Signals(-exitcode).name})"
        return f"died (signal {-exitcode})"
    return f"exited (code {exitcode})"


def _reap(process) -> None:
    """Join ``process``; terminate, then kill it if it does not end within :data:`STOP_TIMEOUT`."""
    process.join(STOP_TIMEOUT)
    if process.is_alive():
        process.terminate()
        process.join(1.0)
    if process.is_alive():
        process.kill()
        process.join()
