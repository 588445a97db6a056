"""A planning worker process of :class:`~maru_planner.runtime.process_pool.ProcessPool`: :func:`worker_main`.

It builds its robot model and :class:`MotionPlanner` once, warms the kernels up, then plans the requests on its
pipe one at a time; its :class:`Inbox` thread reads the pipe meanwhile, so a cancel reaches the plan at once.
The messages on the pipe are listed in :mod:`~maru_planner.runtime.process_pool`.
"""

from __future__ import annotations

import os
import pickle
import queue
import signal
import threading
from collections.abc import Callable
from multiprocessing.connection import Connection

from maru_planner import errors
from maru_planner.monitor import PlanMonitor, Progress
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.types import MotionRequest, MotionResult
from maru_planner.runtime.robot_loading import RobotSource
from maru_planner.runtime.warm_up import warm_up
from maru_planner.scene import Scene


class Inbox:
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


def worker_main(conn: Connection, robot: RobotSource, scene: dict, config: PlannerConfig) -> None:
    """A worker process: build the planner once, then plan until told to stop."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group; the pool stops us
    send_lock = threading.Lock()

    def send(message: tuple) -> None:
        with send_lock:
            conn.send(message)

    inbox = Inbox(conn, send)  # reading already: the pool never blocks on a pipe a building worker leaves full
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
            send(("result", job, portable_result(result)))


def portable_result(result: MotionResult) -> MotionResult:
    """``result`` with an error the pool's process can unpickle (else a RuntimeError with its message)."""
    if result.error is not None:
        try:
            pickle.loads(pickle.dumps(result.error))
        except Exception:  # noqa: BLE001 - any exception a third-party library raised
            result.error = RuntimeError(result.message)
    return result
