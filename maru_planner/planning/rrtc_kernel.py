"""Moved: the RRT-Connect search loop to :mod:`maru_planner.planning.planners.kernels.rrtc`, its collision code (state
and edge validity) to :mod:`maru_planner.collision.kernels`; this path is kept for existing imports."""

from maru_planner.collision.kernels.edge_validity import check_edge, edge_buffers, edge_status
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, COLLIDING, VALID, obstacle_bounds
from maru_planner.collision.kernels.state_validity import (
    CLEAR_BY,
    classify,
    clear_on_shapes,
    pairs_clear_on_shapes,
    work_arrays,
)
from maru_planner.planning.planners.kernels.rng import seed_rng, uniform
from maru_planner.planning.planners.kernels.rrtc import (
    BALANCE,
    CHECKS,
    CONNECT,
    DIRECT,
    DOMAIN_ALPHA,
    DOMAIN_MIN_RADIUS,
    DOMAIN_RADIUS,
    DUPLICATE,
    EXTEND,
    FROM,
    FULL,
    LINK0,
    LINK1,
    N0,
    N1,
    N_AMB,
    NEED_EXACT,
    PENDING,
    PHASE,
    REACHED,
    RUNNING,
    SOLVED,
    STATE_FIELDS,
    TARGET,
    TREE,
    grow,
    new_state,
    run,
    solution_path,
    tuning,
)

__all__ = [
    "AMBIGUOUS", "BALANCE", "CHECKS", "CLEAR_BY", "COLLIDING", "CONNECT", "DIRECT", "DOMAIN_ALPHA", "DOMAIN_MIN_RADIUS",
    "DOMAIN_RADIUS", "DUPLICATE", "EXTEND", "FROM", "FULL", "LINK0", "LINK1", "N0", "N1", "N_AMB", "NEED_EXACT",
    "PENDING", "PHASE", "REACHED", "RUNNING", "SOLVED", "STATE_FIELDS", "TARGET", "TREE", "VALID", "check_edge",
    "classify", "clear_on_shapes", "edge_buffers", "edge_status", "grow", "new_state", "obstacle_bounds",
    "pairs_clear_on_shapes", "run", "seed_rng", "solution_path", "tuning", "uniform", "unpack_robot", "unpack_scene",
    "work_arrays",
]  # fmt: skip
