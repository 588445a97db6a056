"""Hard budgets of base planning: the request's deadline and the size limits checked before allocating.

Every loop that can run long checks a :class:`Deadline` (the numba kernels get ``Deadline.kernel_at``
and compare their clock with its one element); what cannot fit the limits below is refused up front
with :class:`~maru_planner.errors.TooLarge` naming the size and the limit. Cancelling is folded into
the deadline: :meth:`Deadline.terminate` (a :class:`~maru_planner.monitor.PlanMonitor` calls it on
cancel) makes it pass at once, for Python loops and running kernels alike, and the timeout it then
raises is :class:`~maru_planner.errors.PlanningCancelled`.
"""

from __future__ import annotations

import math
import time

import numpy as np

from maru_planner.errors import InvalidRequest, PlanningCancelled, PlanningTimedOut, TooLarge

DEFAULT_TIME_LIMIT = 60.0  # s, when the caller gives none
# 16.8 M cells: a 4096 x 4096 map (205 m square at 5 cm). Bigger maps are refused when loaded.
MAX_MAP_CELLS = 4096 * 4096
# Memory a single search may allocate (SE(2) states, C-space layers, rasterised footprints).
MAX_SEARCH_BYTES = 2 * 1024**3
NEVER = 1e300  # a deadline the kernels never reach (numba wants a float, not inf)


class Deadline:
    """A wall-clock budget; ``check()`` raises PlanningTimedOut once it has passed.

    ``check`` reads the clock every ``every`` calls, cheap enough for inner loops.
    """

    def __init__(self, seconds: float, every: int = 256):
        if not (seconds > 0):
            raise InvalidRequest(f"time limit must be > 0 s, got {seconds}")
        self.seconds = float(seconds)
        self.start = time.perf_counter()
        # The one copy of the deadline: kernels read [0] at each clock check, so terminate() reaches them.
        self.kernel_at = np.array([self.start + seconds if math.isfinite(seconds) else NEVER])
        self.every = every
        self._calls = 0

    @property
    def at(self) -> float:
        """perf_counter() time the budget ends at (-inf once terminated)."""
        return float(self.kernel_at[0])

    @property
    def cancelled(self) -> bool:
        return self.at == -math.inf

    def terminate(self) -> None:
        """Cancel (from any thread): the deadline passes now; what raises for it raises PlanningCancelled."""
        self.kernel_at[0] = -math.inf

    def remaining(self) -> float:
        return self.at - time.perf_counter()

    def expired(self) -> bool:
        return time.perf_counter() > self.at

    def check(self, what: str = "planning") -> None:
        """Raise PlanningTimedOut (naming ``what`` was running) when the budget is spent."""
        self._calls += 1
        if self._calls % self.every == 0 and self.expired():
            self.raise_timeout(what)

    def check_now(self, what: str = "planning") -> None:
        """Like :meth:`check`, reading the clock on every call (between stages)."""
        if self.expired():
            self.raise_timeout(what)

    def reserve(self, seconds: float, what: str) -> None:
        """Raise for the deadline now (timed out, or cancelled) unless ``seconds`` are left for ``what``."""
        if self.remaining() < seconds:
            self.raise_timeout(f"{what} (needs about {seconds:.2f} s, {max(self.remaining(), 0.0):.2f} s left)")

    def raise_timeout(self, what: str) -> None:
        elapsed = time.perf_counter() - self.start
        if self.cancelled:
            raise PlanningCancelled(f"{what} cancelled after {elapsed:.3f} s")
        raise PlanningTimedOut(f"{what} timed out after {elapsed:.3f} s (budget {self.seconds:g} s)")


def unlimited() -> Deadline:
    """A deadline that never passes (for calls outside a planner, e.g. tests and benchmarks)."""
    return Deadline(math.inf)


def check_map_cells(height: int, width: int, what: str) -> None:
    """TooLarge when a height x width map exceeds MAX_MAP_CELLS."""
    if height * width > MAX_MAP_CELLS:
        raise TooLarge(
            f"{what}: {width} x {height} cells is over the limit of {MAX_MAP_CELLS} cells "
            f"({int(math.isqrt(MAX_MAP_CELLS))}^2)"
        )


def check_bytes(needed: float, what: str, advice: str) -> None:
    """TooLarge when ``needed`` bytes exceed MAX_SEARCH_BYTES."""
    if needed > MAX_SEARCH_BYTES:
        limit = MAX_SEARCH_BYTES / 1024**3
        raise TooLarge(f"{what} needs about {needed / 1024**3:.1f} GB, over the {limit:.0f} GB limit: {advice}")
