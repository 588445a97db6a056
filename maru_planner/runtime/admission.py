"""Admission: planning threads behind an expected-wait rule and a bounded count of admitted requests.

A request with a budget (a plan, IK) is refused at once with :class:`~maru_planner.errors.Busy` when the wait it
can expect -- the requests ahead of it x the recent time per request / ``workers`` -- exceeds its budget, so a
burst that fits its budgets is served in full. ``workers + queue_size`` admitted requests (planning or waiting)
are a hard bound on the memory the queue holds; one more is refused as BUSY too. Time spent waiting counts
against the request's own budget (:func:`time_left`). A worker that has waited ``IDLE_RELEASE_DELAY`` for a job,
with none admitted, gives the memory the requests freed back to the system (:mod:`maru_planner.heap`).
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from maru_planner import errors, heap
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


Job = Callable[[WorkerContext], "bool | None"]  # False: its run time says nothing of the next job's (cancelled)
RECENT_WEIGHT = 0.2  # weight of the newest job in the recent time per budgeted job (an exponential average)
IDLE_RELEASE_DELAY = 1.0  # s a worker waits for a job before it gives freed memory back (none admitted)


class WorkerPool:
    """Planning threads, one :class:`WorkerContext` each, behind admission (module doc).

    ``submit(job, budget)`` admits a job unless ``len(contexts) + queue_size`` are planning or waiting or
    its expected wait exceeds ``budget``, else raises ``errors.Busy`` at once. ``close`` lets the admitted
    jobs finish, then the threads end (the runtime swaps in a new pool when its planner settings change).
    """

    def __init__(self, contexts: list[WorkerContext], queue_size: int, name: str = "planner"):
        self.queue_size = queue_size
        self._jobs: queue.SimpleQueue[tuple[Job, bool] | None] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._admitted = 0
        self._recent = 0.0  # s per budgeted job, recently (0 until one has run: a fresh pool admits)
        self._ran_since_release = False
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

    @property
    def recent_job_time(self) -> float:
        """Recent seconds per budgeted job (plans, IK), an exponential average; 0 before the first."""
        with self._lock:
            return self._recent

    def expected_wait(self, ahead: int) -> float:
        """Seconds a job that finds ``ahead`` jobs admitted can expect to wait for a worker."""
        waiting = max(0, ahead + 1 - self.workers)  # those that must finish before a worker frees for it
        return waiting * self._recent / self.workers

    def submit(self, job: Job, budget: float | None = None) -> None:
        """Queue ``job(context)`` for the next free worker; errors.Busy if the queue is full or the job's
        expected wait exceeds ``budget`` (s; None: a job without a budget, its run time not averaged).
        A job returning False (e.g. cancelled) is not averaged either."""
        with self._lock:
            capacity = self.workers + self.queue_size
            if self._admitted >= capacity:
                raise errors.Busy(
                    f"{self._admitted} requests are planning or waiting (workers {self.workers} + "
                    f"queue_size {self.queue_size}); try again later"
                )
            wait = self.expected_wait(self._admitted)
            if budget is not None and wait > budget:
                raise errors.Busy(
                    f"expected wait {wait:.2f} s exceeds the budget {budget:.2f} s ({self._admitted} requests "
                    f"planning or waiting, {self._recent:.3f} s each recently, {self.workers} workers); "
                    "try again later"
                )
            self._admitted += 1
        self._jobs.put((job, budget is not None))

    def close(self) -> None:
        """Finish the admitted jobs, then stop the threads (no new job may be submitted)."""
        for _ in self._threads:
            self._jobs.put(None)

    def _serve(self, context: WorkerContext) -> None:
        while True:
            try:
                item = self._jobs.get(timeout=IDLE_RELEASE_DELAY if self._ran_since_release else None)
            except queue.Empty:
                self._release_freed_memory()
                continue
            if item is None:
                return
            job, budgeted = item
            started = time.monotonic()
            representative = False
            try:
                representative = job(context) is not False
            finally:
                took = time.monotonic() - started
                with self._lock:
                    self._admitted -= 1
                    self._ran_since_release = True
                    if budgeted and representative and took > 1e-4:  # one cancelled while waiting took no time
                        self._recent = (
                            took if self._recent == 0.0 else self._recent + RECENT_WEIGHT * (took - self._recent)
                        )

    def _release_freed_memory(self) -> None:
        """Off every request's path (no job admitted), once per busy spell."""
        with self._lock:
            if self._admitted or not self._ran_since_release:
                return
            self._ran_since_release = False
        heap.release_free_memory()


def time_left(deadline: float, budget_name: str) -> float:
    """Seconds to ``deadline``; PlanningTimedOut if the request used its budget waiting for a worker."""
    left = deadline - time.monotonic()
    if left <= 0.0:
        raise errors.PlanningTimedOut(f"the {budget_name} ran out while the request waited for a worker", source="node")
    return left
