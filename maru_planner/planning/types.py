"""Request, result, status and statistics of a motion-planning call (MoveIt-like, no ROS)."""

from __future__ import annotations

import enum
import math
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from maru_planner import errors
from maru_planner.planning.constraints import PathConstraints
from maru_planner.trajectory.trajectory import Trajectory

if TYPE_CHECKING:  # the sphere module loads numba; results only carry its PathVerification
    from maru_planner.collision.spheres import PathVerification
    from maru_planner.trajectory.report import TimingReport


class PlanStatus(enum.Enum):
    """Outcome of :meth:`MotionPlanner.plan`; every failure has its own code."""

    SUCCESS = "SUCCESS"
    PLANNING_FAILED = "PLANNING_FAILED"
    TIMED_OUT = "TIMED_OUT"
    INVALID_GROUP = "INVALID_GROUP"
    INVALID_PLANNER = "INVALID_PLANNER"
    INVALID_JOINT_NAMES = "INVALID_JOINT_NAMES"
    INVALID_JOINT_COUNT = "INVALID_JOINT_COUNT"
    INVALID_STATE = "INVALID_STATE"
    START_IN_COLLISION = "START_IN_COLLISION"
    GOAL_IN_COLLISION = "GOAL_IN_COLLISION"
    NO_IK_SOLUTION = "NO_IK_SOLUTION"
    INVALID_SCENE = "INVALID_SCENE"
    INVALID_REQUEST = "INVALID_REQUEST"
    NO_START_STATE = "NO_START_STATE"
    INVALID_LINK = "INVALID_LINK"
    INVALID_OBJECT = "INVALID_OBJECT"
    OBJECT_ALREADY_ATTACHED = "OBJECT_ALREADY_ATTACHED"
    START_VIOLATES_CONSTRAINTS = "START_VIOLATES_CONSTRAINTS"
    BUSY = "BUSY"


# Most specific class first: the first isinstance match wins.
_STATUS_OF_ERROR: list[tuple[type[errors.MaruError], PlanStatus]] = [
    (errors.InvalidGroup, PlanStatus.INVALID_GROUP),
    (errors.InvalidPlanner, PlanStatus.INVALID_PLANNER),
    (errors.InvalidJointNames, PlanStatus.INVALID_JOINT_NAMES),
    (errors.InvalidJointCount, PlanStatus.INVALID_JOINT_COUNT),
    (errors.InvalidState, PlanStatus.INVALID_STATE),
    (errors.NoStartState, PlanStatus.NO_START_STATE),
    (errors.InvalidLink, PlanStatus.INVALID_LINK),
    (errors.StartViolatesConstraints, PlanStatus.START_VIOLATES_CONSTRAINTS),
    (errors.InvalidRequest, PlanStatus.INVALID_REQUEST),
    (errors.StartInCollision, PlanStatus.START_IN_COLLISION),
    (errors.GoalInCollision, PlanStatus.GOAL_IN_COLLISION),
    (errors.NoIKSolution, PlanStatus.NO_IK_SOLUTION),
    (errors.ObjectAlreadyAttached, PlanStatus.OBJECT_ALREADY_ATTACHED),
    (errors.InvalidObject, PlanStatus.INVALID_OBJECT),
    (errors.InvalidScene, PlanStatus.INVALID_SCENE),
    (errors.PlanningTimedOut, PlanStatus.TIMED_OUT),
    (errors.PlanningFailed, PlanStatus.PLANNING_FAILED),
    (errors.Busy, PlanStatus.BUSY),
]


def known_status_of_error(error: BaseException) -> PlanStatus | None:
    """The status a typed error maps to; None for an error the table does not know (a bug)."""
    for cls, status in _STATUS_OF_ERROR:
        if isinstance(error, cls):
            return status
    return None


def status_of_error(error: BaseException) -> PlanStatus:
    """The status code a typed error maps to (PLANNING_FAILED for anything unknown)."""
    return known_status_of_error(error) or PlanStatus.PLANNING_FAILED


@dataclass
class MotionRequest:
    """One planning query.

    ``start`` maps joint names to values (the full robot state is fine: joints outside
    the group are held fixed at these values). The goal is either ``goal_joints`` (all
    joints of the group) or ``goal_poses`` ({frame: 4x4 homogeneous matrix}, solved by IK
    first). ``seed=None`` draws a random seed (reported in the stats). ``time_parameterization``
    is "toppra", "ruckig" or "trapezoid" (:mod:`~maru_planner.trajectory`); empty = the
    planner's ``PlannerConfig.time_parameterization``. ``jerk_scaling`` scales the jerk limits
    ("ruckig" only). ``safety_margin`` (m): the clearance the certified path keeps from every
    obstacle and link pair (``docs/certification.md``); None = ``PlannerConfig.safety_margin``.
    ``path_constraints``: kept along the whole motion, planned by CBiRRT
    (:mod:`~maru_planner.planning.constrained_planner`, ``docs/manipulation.md``). ``goal_region``: instead of
    a joint goal, a pose region (orientation tolerances and/or a position box of links) the goal must lie in.
    """

    group: str
    start: dict[str, float] | None = None
    goal_joints: dict[str, float] | None = None
    goal_poses: dict[str, np.ndarray] | None = None
    planner_id: str = ""
    time_budget: float = 5.0
    seed: int | None = None
    attempts: int = 1
    velocity_scaling: float = 1.0
    acceleration_scaling: float = 1.0
    simplify: bool = True
    time_parameterization: str = ""
    jerk_scaling: float = 1.0
    safety_margin: float | None = None
    path_constraints: PathConstraints | None = None
    goal_region: PathConstraints | None = None


@dataclass
class PlanStats:
    """What a planning call cost and produced. Times are seconds, lengths radians."""

    planner_id: str = ""
    nodes: int = 0
    edges: int = 0
    collision_checks: int = 0
    path_length: float = 0.0
    waypoints: int = 0
    smoothness: float = 0.0
    validation_time: float = 0.0
    ik_time: float = 0.0
    solve_time: float = 0.0
    simplify_time: float = 0.0
    parameterize_time: float = 0.0
    total_time: float = 0.0
    seed: int | None = None
    roadmap_build_time: float = 0.0
    roadmap_reused: bool = False
    attempts_used: int = 0
    raw_waypoints: int = 0
    raw_path_length: float = 0.0
    collision_model: str = "exact"  # the checker planned on: "exact" or "spheres"
    verified: bool = False  # "spheres": the returned path was re-checked on the exact model and is free
    verify_time: float = 0.0  # s spent re-checking paths on the exact model (proving them: "spheres" certified)
    replans: int = 0  # re-plans at a finer resolution after a path failed that check
    time_parameterization: str = ""  # the method that made the trajectory (a blended one may fall back)
    # the motion is proven collision-free on the exact model: the path, without the ends of its corners the trajectory
    # rounds with certified blends (MotionResult.corner_blends; docs/certification.md)
    certified: bool = False
    # s spent certifying (all attempts); when the trajectory's whole curve was proven with its blends
    # (MotionResult.curve_proof), the time of that proof, which parameterize_time includes
    certify_time: float = 0.0
    min_clearance: float = math.inf  # m: smallest distance measured while certifying the path and its blends
    repairs: int = 0  # segments that failed certification and were re-planned locally

    def to_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


@dataclass
class MotionResult:
    """Answer to a :class:`MotionRequest`; ``plan`` never raises, it sets ``status``."""

    status: PlanStatus
    message: str = ""
    error: BaseException | None = None
    joint_names: list[str] = field(default_factory=list)
    path: np.ndarray | None = None
    trajectory: Trajectory | None = None
    stats: PlanStats = field(default_factory=PlanStats)
    verification: PathVerification | None = None  # the last exact re-check ("spheres" only)
    # per waypoint of ``path``: the half-length (rad) of the parabolic blend the trajectory rounds it with, proven
    # by the certifier (toppra only; 0: the trajectory passes through it or stops there); None: no such blends
    corner_blends: np.ndarray | None = None
    # the trajectory's whole curve (blends and the straight parts between them) was proven with the blends, by this
    # timing report (its certify_checks, certify_time): the path's certification has nothing left to prove (toppra with
    # a certifier; docs/certification.md)
    curve_proof: TimingReport | None = None

    @property
    def curve_certified(self) -> bool:
        return self.curve_proof is not None

    @property
    def success(self) -> bool:
        return self.status is PlanStatus.SUCCESS

    def to_json_dict(self) -> dict:
        """The ``maru-plan`` JSON shape."""
        return {**answer_json(self), "stats": self.stats.to_dict(), "seed": self.stats.seed}


class PlanAnswer(Protocol):
    """What every planning answer (:class:`MotionResult`, a Cartesian path's result) carries."""

    status: PlanStatus
    message: str
    error: BaseException | None
    joint_names: list[str]
    path: np.ndarray | None
    trajectory: Trajectory | None


def set_failure(answer: PlanAnswer, exc: BaseException) -> None:
    """Make ``answer`` report ``exc``: a typed error's status and message; anything else is an internal error."""
    answer.error = exc
    if isinstance(exc, errors.MaruError):
        answer.status, answer.message = status_of_error(exc), exc.message
    else:
        answer.status, answer.message = PlanStatus.PLANNING_FAILED, f"internal error: {type(exc).__name__}: {exc}"


def answer_json(answer: PlanAnswer) -> dict:
    """The JSON fields every planning answer shares: success, status, message, joint names, path, trajectory."""
    return {
        "success": answer.status is PlanStatus.SUCCESS,
        "status": answer.status.value,
        "message": answer.message,
        "joint_names": list(answer.joint_names),
        "path": [] if answer.path is None else answer.path.tolist(),
        "trajectory": None if answer.trajectory is None else answer.trajectory.to_dict(),
    }
