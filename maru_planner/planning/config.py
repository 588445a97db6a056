"""Plain configuration of the motion planner (the node fills it from ROS parameters)."""

from __future__ import annotations

from dataclasses import dataclass, field


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
    """

    resolution: float = 0.02
    default_planner: str = "RRTConnect"
    planner_params: dict[str, dict] = field(default_factory=dict)
    simplify_max_tries: int = 100
    postprocess_reserve: float = 0.1
    trajectory_dt: float = 0.05
    prm_roadmap_nodes: int = 800

    def __post_init__(self):
        if not self.resolution > 0:
            raise ValueError(f"PlannerConfig.resolution must be > 0 rad, got {self.resolution}")
        if not 0.0 <= self.postprocess_reserve < 1.0:
            raise ValueError(f"PlannerConfig.postprocess_reserve must be in [0, 1), got {self.postprocess_reserve}")
        if not self.trajectory_dt > 0:
            raise ValueError(f"PlannerConfig.trajectory_dt must be > 0 s, got {self.trajectory_dt}")
