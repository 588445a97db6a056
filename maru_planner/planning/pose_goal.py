"""Goal given as frame poses → a collision-free goal configuration by IK.

``robot.ik.solve_ik`` tries the robot's own IK strategies first (its profile's: for Maru-1 the paper's
two-hand scheme and closed-form arms), then damped least squares over the group's joints. Only
solutions the collision checker calls valid are accepted, seeded by the start so the goal stays close to it.
"""

from __future__ import annotations

import time

import numpy as np

from maru_planner import errors
from maru_planner.robot.ik import solve_ik


def solve_pose_goal(robot, checker, group: str, goal_poses: dict, start_full, indices, deadline: float) -> np.ndarray:
    """Full configuration reaching every ``goal_poses`` frame (4x4, root frame); raises NoIKSolution."""
    if not isinstance(goal_poses, dict) or not goal_poses:
        raise errors.InvalidRequest("goal_poses must map frame names to 4x4 poses")
    targets = {}
    for frame, pose in goal_poses.items():
        pose = np.asarray(pose, dtype=float)
        if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
            raise errors.InvalidRequest(f"goal pose of frame {frame} must be a finite 4x4 matrix, got {pose.shape}")
        try:
            robot.frame_id(frame)
        except errors.InvalidRequest as exc:
            raise errors.InvalidRequest(f"goal pose names unknown frame {frame!r}") from exc
        targets[frame] = pose

    def is_valid(q) -> bool:
        return bool(checker.is_valid(q))

    if time.monotonic() >= deadline:
        raise errors.PlanningTimedOut("the time budget ran out before IK", source="ik")
    try:
        return solve_ik(robot, targets, start_full, group, deadline=deadline, is_valid=is_valid)
    except errors.NoIKSolution as exc:
        raise errors.NoIKSolution(f"no collision-free IK solution for {', '.join(targets)}: {exc}") from None
