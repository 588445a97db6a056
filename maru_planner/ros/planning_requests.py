"""``planning_node``'s requests -> the planning runtime's: plans, IK, scene edits; and plan feedback messages.

Fields are checked in the order the node has always checked them, so a request wrong in several ways is
refused for the same one. Joint values come by name; an empty start state is the latest ``/joint_states``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from sensor_msgs.msg import JointState

from maru_planner import errors
from maru_planner.monitor import Progress
from maru_planner.planning import MotionRequest
from maru_planner.planning.requests import MAX_ATTEMPTS
from maru_planner.ros import manipulation
from maru_planner.ros import planning_conversions as conv
from maru_planner.ros.planning_parameters import NodeSettings
from maru_planner.runtime import AddObstacle, IkRequest, MoveObstacle, RemoveObstacle, SceneEdit, ik_timeout
from maru_planner.scene import Obstacle
from maru_planner.trajectory.limits import check_scaling
from maru_planner_interfaces.action import PlanMotion as PlanMotionAction
from maru_planner_interfaces.msg import SceneObstacle
from maru_planner_interfaces.srv import ComputeIK

Latest = Callable[[], dict[str, float]]  # the latest /joint_states values


def motion_request(
    request: Any, settings: NodeSettings, default_planner: str, latest: Latest, robot: Any = None
) -> MotionRequest:
    """Core ``MotionRequest`` of a ``PlanMotion`` request or goal (raises typed errors for bad fields).

    ``robot`` (the runtime's, read-only): places the links of a relative-pose constraint held at the start.
    """
    budget = float(request.allowed_planning_time)
    if not math.isfinite(budget) or budget <= 0.0:
        raise errors.InvalidRequest(f"allowed_planning_time must be > 0 s, got {budget}")
    if budget > settings.max_planning_time:
        raise errors.InvalidRequest(
            f"allowed_planning_time {budget} s exceeds max_planning_time {settings.max_planning_time} s"
        )
    start = start_state(request.start_state, latest)
    goal_joints = None
    if request.goal_joint_names or request.goal_positions:
        goal_joints = conv.named_values(request.goal_joint_names, request.goal_positions, "goal")
    goal_poses = None
    if request.goal_poses or request.goal_links:
        goal_poses = conv.pose_goals(request.goal_poses, request.goal_links, settings.planning_frame)
    if goal_joints is None and goal_poses is None:
        raise errors.InvalidRequest("no goal: give goal_joint_names + goal_positions or goal_poses + goal_links")
    if goal_joints is not None and goal_poses is not None:
        raise errors.InvalidRequest("give either a joint goal or pose goals, not both")
    # kept along the motion; planned by CBiRRT, which an empty planner id then means
    constraints = manipulation.path_constraints(request.path_constraints, settings.planning_frame, robot, start)
    return MotionRequest(
        group=request.group or settings.default_group,
        start=start,
        goal_joints=goal_joints,
        goal_poses=goal_poses,
        planner_id=request.planner_id or ("" if not constraints.empty else default_planner),
        time_budget=budget,
        seed=plan_seed(request.seed),
        attempts=plan_attempts(request.num_attempts, settings.default_attempts),
        velocity_scaling=scaling(request.max_velocity_scaling_factor, "max_velocity_scaling_factor"),
        acceleration_scaling=scaling(request.max_acceleration_scaling_factor, "max_acceleration_scaling_factor"),
        time_parameterization=request.time_parameterization,
        jerk_scaling=scaling(request.max_jerk_scaling_factor, "max_jerk_scaling_factor"),
        path_constraints=constraints,
    )


def start_state(msg: JointState, latest: Latest) -> dict[str, float]:
    """The joint values of ``msg``; empty: the latest ``/joint_states`` (NoStartState if none came)."""
    if msg.name or msg.position:
        return conv.joint_state_values(msg, "start_state")
    values = latest()
    if not values:
        raise errors.NoStartState("start_state is empty and no /joint_states message has been received")
    return values


def plan_seed(value: int) -> int | None:
    """A request's seed: -1 means a random one (None); other negative values are refused."""
    if value < -1:
        raise errors.InvalidRequest(f"seed must be in [0, 2^63) or -1 (random), got {value}")
    return None if value == -1 else int(value)


def plan_attempts(value: int, default: int) -> int:
    """A request's ``num_attempts``: 0 means the node's ``default_attempts``; negative or past MAX_ATTEMPTS
    is refused."""
    if not 0 <= value <= MAX_ATTEMPTS:
        raise errors.InvalidRequest(
            f"num_attempts must be in [1, {MAX_ATTEMPTS}] (0 = the node's default_attempts), got {value}"
        )
    return int(value) if value > 0 else default


def scaling(value: float, field: str) -> float:
    """A request's scaling factor ``field``: 0 means 1.0, else checked as the core checks it."""
    return 1.0 if value == 0.0 else check_scaling(value, field)


def ik_request(request: ComputeIK.Request, settings: NodeSettings, latest: Latest) -> IkRequest:
    """The runtime's IK request of a ``ComputeIK`` request (its seed: the request's, else /joint_states)."""
    targets = conv.pose_goals(request.poses, request.links, settings.planning_frame)
    if not targets:
        raise errors.InvalidRequest("no poses: give poses + links")
    if request.seed_state.name or request.seed_state.position:
        seed, strict = conv.joint_state_values(request.seed_state, "seed_state"), True
    else:
        seed, strict = latest(), False
    timeout = ik_timeout(request.timeout, settings.ik_timeout, settings.max_planning_time)
    group = request.group or settings.default_group
    return IkRequest(group, targets, seed, timeout, strict, request.avoid_collisions)


def feedback_msg(progress: Progress) -> PlanMotionAction.Feedback:
    return PlanMotionAction.Feedback(
        stage=progress.stage,
        elapsed=float(progress.elapsed),
        nodes=int(progress.info.get("nodes", 0)),
        best_cost=float(progress.info.get("best_cost", math.nan)),
    )


# ---------------------------------------------------------------- scene edits


def scene_edits(obstacles: Iterable[SceneObstacle], frame: str) -> Iterator[SceneEdit]:
    """The edits of ``SceneObstacle`` messages, each converted when the scene store asks for it."""
    for msg in obstacles:
        yield scene_edit(msg, frame)


def scene_edit(msg: SceneObstacle, frame: str) -> SceneEdit:
    """One ADD/MOVE/REMOVE/ATTACH/DETACH (raises InvalidScene naming the obstacle).

    Obstacle poses must be in ``frame`` (the planning frame) or have an empty frame_id.
    """
    if not msg.name:
        raise errors.InvalidScene("obstacle has an empty name")
    if msg.operation != SceneObstacle.REMOVE and msg.header.frame_id not in ("", frame):
        raise errors.InvalidScene(
            f"obstacle '{msg.name}' is in frame '{msg.header.frame_id}'; only '{frame}' is supported (no tf here)"
        )
    if msg.operation == SceneObstacle.REMOVE:
        return RemoveObstacle(msg.name)
    if msg.operation == SceneObstacle.MOVE:
        return MoveObstacle(msg.name, conv.obstacle_pose(msg.pose, msg.name))
    if msg.operation == SceneObstacle.ADD:
        return AddObstacle(Obstacle.from_dict(conv.primitive_to_obstacle(msg.name, msg.shape, msg.pose)))
    if msg.operation in (SceneObstacle.ATTACH, SceneObstacle.DETACH):
        return manipulation.attachment_edit(msg)
    raise errors.InvalidScene(
        f"obstacle '{msg.name}': operation {msg.operation} is not ADD, MOVE, REMOVE, ATTACH or DETACH"
    )
