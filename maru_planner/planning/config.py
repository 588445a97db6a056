"""Plain configuration of the motion planner (the node fills it from ROS parameters)."""

from __future__ import annotations

from dataclasses import dataclass, field

from maru_planner.params import param

COLLISION_MODELS = ("exact", "spheres")
TIME_PARAMETERIZATIONS = ("toppra", "ruckig", "trapezoid")  # see maru_planner.planning.timing


@dataclass
class PlannerConfig:
    """Settings of :class:`~maru_planner.planning.MotionPlanner`.

    resolution: motion-check step, the largest joint move (rad) between two checked states.
    default_planner: planner id used when a request leaves ``planner_id`` empty.
    planner_params: per-id named parameters overriding the registry defaults.
    simplify_max_tries: consecutive failed random shortcuts before simplification stops.
    postprocess_reserve: share of the time budget held back from the search for simplification
        and time parameterisation (the search gets the rest; unused reserve is not lost).
    trajectory_dt: sample period of the time-parameterised trajectory (s).
    prm_roadmap_nodes: milestones a PRM roadmap is grown to before its first query (paper: ~780).
    collision_model: the checker :func:`~maru_planner.planning.checkers.make_checkers` (and so
        ``MotionPlanner.from_scene``, ``maru-plan``, ``planning_node``) builds: "exact" (pinocchio + coal
        on the URDF's collision geometry) or "spheres" (the batched sphere checker; every path it plans
        is re-checked on the exact model before it is returned). A planner given a checker directly
        plans on that checker; a sphere checker is always verified.
    verify_resolution: joint step (rad) of that re-check; None = a quarter of ``resolution``.
    max_refinements: re-plans, each at half the previous ``resolution``, after a path fails
        verification (within the same time budget); then the request fails (PLANNING_FAILED).
    time_parameterization, blend_deviation, max_trajectory_points: see their ``param`` descriptions
        and :mod:`maru_planner.planning.timing`.
    """

    resolution: float = 0.02
    default_planner: str = "RRTConnect"
    planner_params: dict[str, dict] = field(default_factory=dict)
    simplify_max_tries: int = 100
    postprocess_reserve: float = 0.1
    trajectory_dt: float = 0.05
    prm_roadmap_nodes: int = 800
    collision_model: str = "exact"
    verify_resolution: float | None = None
    max_refinements: int = 2
    time_parameterization: str = param(
        "toppra",
        "time parameterisation of a request that names none: toppra (time-optimal through blended corners), "
        "ruckig (jerk-limited through blended corners) or trapezoid (rest at every waypoint)",
        choices=TIME_PARAMETERIZATIONS,
    )
    blend_deviation: float = param(
        0.5,
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

    def __post_init__(self):
        if not self.resolution > 0:
            raise ValueError(f"PlannerConfig.resolution must be > 0 rad, got {self.resolution}")
        if not 0.0 <= self.postprocess_reserve < 1.0:
            raise ValueError(f"PlannerConfig.postprocess_reserve must be in [0, 1), got {self.postprocess_reserve}")
        if not self.trajectory_dt > 0:
            raise ValueError(f"PlannerConfig.trajectory_dt must be > 0 s, got {self.trajectory_dt}")
        if self.collision_model not in COLLISION_MODELS:
            raise ValueError(
                f"PlannerConfig.collision_model must be one of {', '.join(COLLISION_MODELS)}, "
                f"got {self.collision_model!r}"
            )
        if self.verify_resolution is not None and not self.verify_resolution > 0:
            raise ValueError(f"PlannerConfig.verify_resolution must be > 0 rad, got {self.verify_resolution}")
        if self.max_refinements < 0:
            raise ValueError(f"PlannerConfig.max_refinements must be >= 0, got {self.max_refinements}")
        if self.time_parameterization not in TIME_PARAMETERIZATIONS:
            raise ValueError(
                f"PlannerConfig.time_parameterization must be one of {', '.join(TIME_PARAMETERIZATIONS)}, "
                f"got {self.time_parameterization!r}"
            )
        if not 0.0 <= self.blend_deviation <= 3.0:
            raise ValueError(f"PlannerConfig.blend_deviation must be in [0, 3] rad, got {self.blend_deviation}")
        if self.max_trajectory_points < 2:
            raise ValueError(f"PlannerConfig.max_trajectory_points must be >= 2, got {self.max_trajectory_points}")

    @property
    def verify_step(self) -> float:
        """The joint step of the exact re-check of a sphere-checker path."""
        return self.verify_resolution or 0.25 * self.resolution
