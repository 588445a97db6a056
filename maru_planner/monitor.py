"""Watching and cancelling a running plan: :class:`PlanMonitor` (pure core, thread-safe).

A caller (an action server, a CLI, a test) hands a monitor to a planner; the planner reports its
stage and progress through it and stops when it is cancelled:

* OMPL searches register their termination condition with :meth:`PlanMonitor.attach`, so
  :meth:`PlanMonitor.cancel` from any thread ends ``solve(ptc)`` at OMPL's next check — no Python
  callback runs inside the search loop;
* Python loops (grid searches, shortcutting, time parameterisation) call :meth:`PlanMonitor.check`,
  which raises :class:`~maru_planner.errors.PlanningCancelled`, or read :attr:`PlanMonitor.cancelled`.

``report(stage, **progress)`` forwards a :class:`Progress` to the ``on_progress`` callback (the action
server turns it into feedback); it never raises into the planner.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Protocol

from maru_planner.errors import PlanningCancelled

_log = logging.getLogger(__name__)


class Terminable(Protocol):
    """What :meth:`PlanMonitor.attach` needs: OMPL's ``PlannerTerminationCondition`` has it."""

    def terminate(self) -> None: ...


@dataclass(frozen=True)
class Progress:
    """One progress report: the stage, seconds since the monitor started, and stage-specific numbers.

    ``info`` holds e.g. ``nodes`` (tree or roadmap size), ``best_cost`` (path length so far),
    ``expansions`` (grid searches).
    """

    stage: str
    elapsed: float
    info: dict[str, Any] = field(default_factory=dict)


class PlanMonitor:
    """Cancel flag + progress sink shared between a planner and whoever waits for it (module doc)."""

    def __init__(self, on_progress: Callable[[Progress], None] | None = None):
        self._on_progress = on_progress
        self._cancelled = threading.Event()
        self._lock = threading.Lock()
        self._attached: list[Terminable] = []
        self._started = time.monotonic()
        self.stage = "queued"
        self.info: dict[str, Any] = {}

    # --- cancellation -----------------------------------------------------------------------
    @property
    def cancelled(self) -> bool:
        return self._cancelled.is_set()

    def cancel(self) -> None:
        """Ask the planner to stop: terminates attached OMPL searches at once, loops at their next check."""
        self._cancelled.set()
        with self._lock:
            attached = list(self._attached)
        for condition in attached:
            condition.terminate()

    def check(self) -> None:
        """Raise :class:`PlanningCancelled` if :meth:`cancel` was called."""
        if self._cancelled.is_set():
            raise PlanningCancelled(f"cancelled during {self.stage}", source="planner")

    @contextmanager
    def attach(self, condition: Terminable) -> Iterator[Terminable]:
        """Within the block, :meth:`cancel` also terminates ``condition`` (e.g. an OMPL PTC)."""
        with self._lock:
            self._attached.append(condition)
        if self._cancelled.is_set():
            condition.terminate()
        try:
            yield condition
        finally:
            with self._lock:
                self._attached.remove(condition)

    # --- progress ---------------------------------------------------------------------------
    @property
    def elapsed(self) -> float:
        return time.monotonic() - self._started

    def report(self, stage: str, **info: Any) -> None:
        """Record the current stage (and numbers) and pass them to ``on_progress``; checks cancellation."""
        self.stage = stage
        if info:
            self.info.update(info)
        if self._on_progress is not None:
            try:
                self._on_progress(Progress(stage, self.elapsed, dict(self.info)))
            except Exception:  # noqa: BLE001 - a broken feedback sink must not break the plan
                _log.exception("progress callback failed")
        self.check()

    def snapshot(self) -> Progress:
        """The latest stage and numbers (for periodic feedback from another thread)."""
        return Progress(self.stage, self.elapsed, dict(self.info))
