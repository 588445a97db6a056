"""Admission: planning threads behind a bounded count of admitted requests (BUSY beyond it).

At most ``workers + queue_size`` requests are admitted (planning or waiting); one more is refused at once with
:class:`~maru_planner.errors.Busy`. Time spent waiting counts against the request's own budget
(:func:`time_left`).
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from maru_planner import errors
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.runtime.process_pool import ProcessPool


@dataclass
class WorkerContext:
    """Everything one worker thread needs to plan: its own planner (robot model, checker) at ``scene_version``.

    With ``processes`` (``worker_processes``), plans go to those worker processes; the thread's own
    planner answers IK, FK and validity checks.
    """

    planner: MotionPlanner
    scene_version: int
    processes: ProcessPool | None = None


class WorkerPool:
    """Planning threads, one :class:`WorkerContext` each, behind a bounded admission count.

    ``submit`` admits a job while fewer than ``len(contexts) + queue_size`` are planning or
    waiting, else raises ``errors.Busy`` at once. ``close`` lets the admitted jobs finish,
    then the threads end (the runtime swaps in a new pool when its planner settings change).
    """

    def __init__(self, contexts: list[WorkerContext], queue_size: int, name: str = "planner"):
        self.queue_size = queue_size
        self._jobs: queue.SimpleQueue[Callable[[WorkerContext], None] | None] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._admitted = 0
        self._threads = [
            threading.Thread(target=self._serve, args=(context,), name=f"{name}-{i}", daemon=True)
            for i, context in enumerate(contexts)
        ]
        for thread in self._threads:
            thread.start()

    @property
    def workers(self) -> int:
        return len(self._threads)

    @property
    def admitted(self) -> int:
        """Jobs planning or waiting."""
        with self._lock:
            return self._admitted

    def submit(self, job: Callable[[WorkerContext], None]) -> None:
        """Queue ``job(context)`` for the next free worker; errors.Busy if the queue is full."""
        with self._lock:
            capacity = self.workers + self.queue_size
            if self._admitted >= capacity:
                raise errors.Busy(
                    f"{self._admitted} requests are planning or waiting (workers {self.workers} + "
                    f"queue_size {self.queue_size}); try again later"
                )
            self._admitted += 1
        self._jobs.put(job)

    def close(self) -> None:
        """Finish the admitted jobs, then stop the threads (no new job may be submitted)."""
        for _ in self._threads:
            self._jobs.put(None)

    def _serve(self, context: WorkerContext) -> None:
        while (job := self._jobs.get()) is not None:
            try:
                job(context)
            finally:
                with self._lock:
                    self._admitted -= 1


def time_left(deadline: float, budget_name: str) -> float:
    """Seconds to ``deadline``; PlanningTimedOut if the request used its budget waiting for a worker."""
    left = deadline - time.monotonic()
    if left <= 0.0:
        raise errors.PlanningTimedOut(f"the {budget_name} ran out while the request waited for a worker", source="node")
    return left
