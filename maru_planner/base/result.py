"""Result of a mobile-base planner (A*, SE(2) A*, MSPP, tunnel, biped)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

# Status strings shared by every base planner; nodes map them to error codes.
SOLVED = "solved"
NO_PATH = "no_path"  # the search finished without a path
NO_PATH_PROVEN = "no_path_proven"  # decided without search (e.g. ECA: start or goal enclosed)
START_OCCUPIED = "start_occupied"
GOAL_OCCUPIED = "goal_occupied"
START_OUTSIDE_MAP = "start_outside_map"
GOAL_OUTSIDE_MAP = "goal_outside_map"
TIMED_OUT = "timed_out"
INVALID_REQUEST = "invalid_request"

STATUSES = (
    SOLVED,
    NO_PATH,
    NO_PATH_PROVEN,
    START_OCCUPIED,
    GOAL_OCCUPIED,
    START_OUTSIDE_MAP,
    GOAL_OUTSIDE_MAP,
    TIMED_OUT,
    INVALID_REQUEST,
)


@dataclass
class BasePlanResult:
    """What every base planner returns.

    ``path`` is an (n, 3) array of (x, y, theta) in the map frame (metres,
    radians), first row = start, last row = goal; empty (0, 3) on failure.
    ``stats`` holds at least ``expansions``, ``collision_checks``,
    ``planning_time`` and ``deciding_stage``; planners add their own keys.
    ``layers`` carries arrays worth drawing (grown maps, tunnels, ...).
    """

    status: str
    message: str
    path: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    stats: dict = field(default_factory=dict)
    layers: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"unknown base-planner status {self.status!r}; expected one of {STATUSES}")
        self.path = np.asarray(self.path, dtype=float).reshape(-1, 3)

    @property
    def success(self) -> bool:
        return self.status == SOLVED

    def path_length(self) -> float:
        if len(self.path) < 2:
            return 0.0
        return float(np.sum(np.linalg.norm(np.diff(self.path[:, :2], axis=0), axis=1)))


def jsonable(value):
    """``value`` with numpy arrays/scalars as plain lists/numbers and non-finite floats as None (strict JSON)."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
