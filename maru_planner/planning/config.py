"""Plain configuration of the motion planner: each field declared once, with its documentation and limits.

:data:`PLANNER_CONFIG_PARAMS` (one :class:`~maru_planner.params.ParamSpec` per field) is what
``planning_node`` declares as ROS parameters and what ``PlannerConfig`` checks its values against.
"""

from __future__ import annotations

from dataclasses import dataclass

from maru_planner.params import ParamSpec, dataclass_params, param
from maru_planner.trajectory.limits import METHODS as TIME_PARAMETERIZATIONS

COLLISION_MODELS = ("exact", "spheres")


@dataclass
class PlannerConfig:
    """Settings of :class:`~maru_planner.planning.MotionPlanner` (see each field's description).

    collision_model: the checker :func:`~maru_planner.planning.checkers.make_checkers` (and so
    ``MotionPlanner.from_scene``, ``maru-plan``, ``planning_node``) builds: "spheres" (the default: the
    batched sphere checker, whose near contacts are decided on the exact model, so each state gets the
    exact model's answer; every path it plans is re-checked on the exact model before it is returned)
    or "exact" (pinocchio + coal on the URDF's collision geometry). A planner given a checker directly
    plans on that checker; a sphere checker is always verified.

    default_planner: "CompiledRRTConnect" (RRT-Connect in a numba kernel on the sphere model; on any
    other checker it runs OMPL's RRTConnect instead, so it is a valid default for "exact" too).

    Out-of-range values raise InvalidRequest (a ValueError) naming the field.
    """

    resolution: float = param(
        0.02, "motion-check step: the largest joint move (rad) between two checked states", lower=1e-4, upper=3.0
    )
    default_planner: str = param(
        "CompiledRRTConnect",
        "planner id used when a request leaves planner_id empty (CompiledRRTConnect: the numba kernel on the "
        "spheres, OMPL's RRTConnect on the exact checker)",
    )
    planner_params: dict[str, dict] = param(
        default_factory=dict, description="per planner id, named parameters overriding the registry defaults"
    )
    simplify_max_tries: int = param(
        100, "consecutive failed random shortcuts before path simplification stops", lower=0, upper=100000
    )
    postprocess_reserve: float = param(
        0.1,
        "share of the time budget held back from the search for simplification and time parameterisation "
        "(unused reserve is not lost)",
        lower=0.0,
        upper=0.9,
    )
    trajectory_dt: float = param(0.05, "sample period of the time-parameterised trajectory (s)", lower=1e-3, upper=1.0)
    prm_roadmap_nodes: int = param(
        800, "milestones a PRM roadmap is grown to before its first query (paper: ~780)", lower=0, upper=1000000
    )
    collision_model: str = param(
        "spheres",
        "checker planned on: spheres (fast; near contacts decided and paths re-checked on the exact model) or "
        "exact (coal on the URDF collision geometry)",
        choices=COLLISION_MODELS,
    )
    verify_resolution: float | None = param(
        None, "joint step (rad) of the exact re-check of a spheres path; unset = resolution / 4", lower=1e-5, upper=3.0
    )
    max_refinements: int = param(
        2,
        "re-plans after a path fails the exact re-check, in the same budget: local repairs of the failing "
        "segment when certifying, else whole re-plans at half the previous resolution",
        lower=0,
        upper=20,
    )
    time_parameterization: str = param(
        "toppra",
        "time parameterisation of a request that names none: toppra (time-optimal through blended corners), "
        "ruckig (jerk-limited through blended corners) or trapezoid (rest at every waypoint)",
        choices=TIME_PARAMETERIZATIONS,
    )
    blend_deviation: float = param(
        0.8,
        "largest distance (rad) of a blended corner from the path's corner; blends are re-checked for collision "
        "and shrunk (or the motion stops there) when they collide; 0 = stop at every waypoint",
        lower=0.0,
        upper=3.0,
    )
    max_trajectory_points: int = param(
        10_000,
        "most samples in a trajectory: the sample period grows past trajectory_dt when a slow motion needs more",
        lower=2,
        upper=1_000_000,
    )
    certify: bool = param(
        True,
        "prove every returned arm path collision-free on the exact model and repair failing segments "
        "(docs/certification.md); false = discrete checks only",
    )
    safety_margin: float = param(
        0.01,
        "clearance (m) a certified path keeps from every obstacle and checked link pair (MoveIt's padding); "
        "a start or goal closer than that lowers it to half their clearance",
        lower=0.0,
        upper=0.5,
    )
    certify_timeout: float = param(
        1.0, "longest certification (s) of one plan, past the request's time budget if need be", lower=1e-3, upper=60.0
    )

    def __post_init__(self) -> None:
        for name, spec in PLANNER_CONFIG_PARAMS.items():
            setattr(self, name, spec.check(getattr(self, name)))

    @property
    def verify_step(self) -> float:
        """The joint step of the exact re-check of a sphere-checker path."""
        return self.verify_resolution or 0.25 * self.resolution


#: One spec per scalar field (``planner_params`` is per planner: the node declares ``planners.<ID>.<name>``).
PLANNER_CONFIG_PARAMS: dict[str, ParamSpec] = dataclass_params(PlannerConfig, skip=("planner_params",))
