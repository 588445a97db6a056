"""What every base planner returns: status (mapped once from the core's typed errors), path, stats, layers."""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from maru_planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidRequest,
    MaruError,
    NoPath,
    NoPathProven,
    PlanningCancelled,
    PlanningTimedOut,
    StartOccupied,
    StartOutsideMap,
)


class PlanStatus(enum.StrEnum):
    """Outcome of a base plan; the value is what the CLI's JSON and ``stats_json`` carry."""

    SOLVED = "solved"
    NO_PATH = "no_path"  # the search finished without a path
    NO_PATH_PROVEN = "no_path_proven"  # decided without search (e.g. ECA: start or goal enclosed)
    START_OCCUPIED = "start_occupied"
    GOAL_OCCUPIED = "goal_occupied"
    START_OUTSIDE_MAP = "start_outside_map"
    GOAL_OUTSIDE_MAP = "goal_outside_map"
    TIMED_OUT = "timed_out"
    CANCELLED = "cancelled"  # the caller cancelled the plan (a PlanMonitor), e.g. an action goal's cancel
    INVALID_REQUEST = "invalid_request"


# Most specific class first: the first class an error is an instance of gives its status.
_ERROR_STATUS: tuple[tuple[type[MaruError], PlanStatus], ...] = (
    (NoPathProven, PlanStatus.NO_PATH_PROVEN),
    (NoPath, PlanStatus.NO_PATH),
    (PlanningTimedOut, PlanStatus.TIMED_OUT),
    (PlanningCancelled, PlanStatus.CANCELLED),
    (StartOccupied, PlanStatus.START_OCCUPIED),
    (GoalOccupied, PlanStatus.GOAL_OCCUPIED),
    (StartOutsideMap, PlanStatus.START_OUTSIDE_MAP),
    (GoalOutsideMap, PlanStatus.GOAL_OUTSIDE_MAP),
    (InvalidRequest, PlanStatus.INVALID_REQUEST),
)


def status_of(error: MaruError) -> PlanStatus:
    """The status a core error reports (the one place errors become statuses)."""
    for cls, status in _ERROR_STATUS:
        if isinstance(error, cls):
            return status
    raise TypeError(f"{type(error).__name__} is not a base-planning outcome: {error}")


@dataclass
class PlanStats:
    """Counters every base planner fills; planners subclass it for their own (JSON keys = field names).

    ``cost`` is the path cost in metres when the planner has one (None otherwise): the length, plus
    ``cost_travel_multiplier`` times the cost along it for a cost-aware plan (before smoothing).
    ``smoothing`` (when the path was smoothed): stretches, sweeps, vertices moved, accepted.
    """

    expansions: int = 0
    collision_checks: int = 0
    planning_time: float = 0.0
    deciding_stage: str = ""
    cost: float | None = None
    smoothing: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict; fields that are None are left out."""
        return {k: v for k, v in jsonable(dataclasses.asdict(self)).items() if v is not None}


def empty_path() -> np.ndarray:
    return np.zeros((0, 3))


@dataclass
class BasePlanResult:
    """What every base planner returns.

    ``path`` is an (n, 3) array of (x, y, theta) in the map frame (metres,
    radians), first row = start, last row = goal; empty (0, 3) on failure.
    ``layers`` carries arrays worth drawing (grown maps, tunnels, ...), also on failure.
    """

    status: PlanStatus
    message: str
    path: np.ndarray = field(default_factory=empty_path)
    stats: PlanStats = field(default_factory=PlanStats)
    layers: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.status = PlanStatus(self.status)
        self.path = np.asarray(self.path, dtype=float).reshape(-1, 3)

    @property
    def success(self) -> bool:
        return self.status is PlanStatus.SOLVED

    def path_length(self) -> float:
        if len(self.path) < 2:
            return 0.0
        return float(np.sum(np.linalg.norm(np.diff(self.path[:, :2], axis=0), axis=1)))


def jsonable(value: Any) -> Any:
    """``value`` with numpy arrays/scalars as plain lists/numbers and non-finite floats as None (strict JSON)."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
