"""Goal given as hand poses → a collision-free goal configuration by IK.

For Maru-1's ``upper_body`` with both hands given, the paper's scheme is used first (waist angle
from the hands' midpoint, eq. 5–6, then each arm: ``two_hand_ik``); otherwise, or if that fails,
damped-least-squares IK over the group's joints (``solve_ik``). Both only accept solutions the
collision checker calls valid, seeded by the start so the goal stays close to it.
"""

from __future__ import annotations

import time

import numpy as np

from maru_planner import errors


def solve_pose_goal(robot, checker, group: str, goal_poses: dict, start_full, indices, deadline: float) -> np.ndarray:
    """Full configuration reaching every ``goal_poses`` frame (4x4, root frame); raises NoIKSolution."""
    from maru_planner.robot.ik import solve_ik, two_hand_ik

    if not isinstance(goal_poses, dict) or not goal_poses:
        raise errors.InvalidRequest("goal_poses must map frame names to 4x4 poses")
    targets = {}
    for frame, pose in goal_poses.items():
        pose = np.asarray(pose, dtype=float)
        if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
            raise errors.InvalidRequest(f"goal pose of frame {frame} must be a finite 4x4 matrix, got {pose.shape}")
        try:
            robot.frame_id(frame)
        except Exception as exc:
            raise errors.InvalidRequest(f"goal pose names unknown frame {frame!r}") from exc
        targets[frame] = pose

    def is_valid(q) -> bool:
        return bool(checker.is_valid(q))

    if time.monotonic() >= deadline:
        raise errors.PlanningTimedOut("the time budget ran out before IK", source="ik")
    ee = getattr(robot, "end_effectors", {})
    right, left = ee.get("right"), ee.get("left")
    errors_seen = []
    if group == "upper_body" and set(targets) == {right, left}:
        try:
            return two_hand_ik(robot, targets[right], targets[left], start_full, deadline=deadline, is_valid=is_valid)
        except errors.NoIKSolution as exc:
            errors_seen.append(str(exc))
    try:
        return solve_ik(robot, targets, start_full, group, deadline=deadline, is_valid=is_valid)
    except errors.NoIKSolution as exc:
        errors_seen.append(str(exc))
    raise errors.NoIKSolution(f"no collision-free IK solution for {', '.join(targets)}: {'; '.join(errors_seen)}")
