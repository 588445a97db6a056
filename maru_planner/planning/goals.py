"""A request's goal as a full configuration: its joint goal (checked), IK of its goal poses, or a state sampled
in its goal region."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from maru_planner import errors
from maru_planner.planning.constraints import goal_in_region
from maru_planner.planning.pose_goal import solve_pose_goal
from maru_planner.planning.requests import check_values
from maru_planner.planning.types import MotionRequest


def goal_configuration(robot: Any, checker: Any, request: MotionRequest, start_full: np.ndarray, indices: Any,
                       deadline: float) -> np.ndarray:  # fmt: skip
    """The full goal configuration of ``request``; joints outside the group keep their start values."""
    if request.goal_poses:
        if request.goal_joints:
            raise errors.InvalidRequest("give either goal_joints or goal_poses, not both")
        return solve_pose_goal(robot, checker, request.group, request.goal_poses or {}, start_full, indices, deadline)
    region = getattr(request, "goal_region", None)
    if region is not None and not region.empty:
        if request.goal_joints:
            raise errors.InvalidRequest("give either goal_joints or goal_region, not both")
        rng = np.random.default_rng(request.seed)
        region_deadline = time.monotonic() + float(request.time_budget) / 2
        return goal_in_region(robot, region, start_full, np.asarray(indices), checker.is_valid, rng, region_deadline)
    return joint_goal(robot, request, start_full, indices)


def joint_goal(robot: Any, request: MotionRequest, start_full: np.ndarray, indices: Any) -> np.ndarray:
    """``request.goal_joints`` over ``start_full``: every joint of the group, no other, each within its limits."""
    if request.goal_joints is None:
        raise errors.InvalidRequest("no goal: give goal_joints or goal_poses")
    values = check_values(robot, request.goal_joints, "goal")
    in_group = set(indices)
    outside = [robot.joint_names[i] for i in values if i not in in_group]
    if outside:
        raise errors.InvalidJointNames(f"goal names joint(s) outside group {request.group}: {', '.join(outside)}")
    if len(values) != len(indices):
        missing = [robot.joint_names[i] for i in indices if i not in values]
        raise errors.InvalidJointCount(
            f"goal has {len(values)} value(s) for group {request.group} of {len(indices)} joints; "
            f"missing: {', '.join(missing)}"
        )
    q = start_full.copy()
    for i, v in values.items():
        q[i] = v
    return q
