"""The messages of arm_sim_node's two execution actions: its own ``ExecuteTrajectory`` and ros2_control's
``control_msgs/action/FollowJointTrajectory`` (what joint_trajectory_controller serves on a real robot).

Both goals carry the same fields the node reads (``trajectory``, ``path_tolerance``, ``goal_tolerance`` of
JointTolerance with ``name``/``position``/``velocity``, ``goal_time_tolerance``), so one executor serves both;
an :class:`ActionShape` builds each action's result and feedback. The error codes are control_msgs' (SUCCESSFUL 0,
INVALID_GOAL -1, INVALID_JOINTS -2, OLD_HEADER_TIMESTAMP -3, PATH/GOAL_TOLERANCE_VIOLATED -4/-5), the same numbers
in both actions. A FollowJointTrajectory goal with a multi-DOF part is refused with INVALID_JOINTS: the arm has
no planar or floating joints. control_msgs has no wheel here; ``scripts/build_interfaces.sh`` builds a stand-in with
upstream's text (``interfaces/control_msgs``) when no real one is importable, and :func:`follow_joint_trajectory_type`
is None when neither is.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from trajectory_msgs.msg import JointTrajectoryPoint

from maru_planner.errors import InvalidJointNames, one_line
from maru_planner.execution.executor import ExecutionResult
from maru_planner_interfaces.action import ExecuteTrajectory


def follow_joint_trajectory_type() -> Any | None:
    """control_msgs' FollowJointTrajectory action class, or None when control_msgs is not installed."""
    try:
        from control_msgs.action import (  # type: ignore[import-untyped]  # lazy: optional package (no wheel)
            FollowJointTrajectory,
        )
    except ImportError:
        return None
    return FollowJointTrajectory


class ActionShape:
    """One execution action's messages: ``kind`` is its action class."""

    def __init__(self, kind: Any):
        self.kind = kind

    def check(self, request: Any) -> None:
        """Raise a MaruError for what the goal asks that this arm cannot do (nothing, by default)."""

    def refused(self, code: int, message: str) -> Any:
        return self.kind.Result(error_code=code, error_string=one_line(message))

    def finished(self, code: int, message: str, result: ExecutionResult) -> Any:
        return self.refused(code, message)

    def feedback(self, stamp: Any, names: list[str], desired: np.ndarray, actual: np.ndarray) -> Any:
        msg = self.kind.Feedback()
        msg.header.stamp = stamp
        msg.joint_names = list(names)
        msg.desired = JointTrajectoryPoint(positions=desired.tolist())
        msg.actual = JointTrajectoryPoint(positions=actual.tolist())
        msg.error = JointTrajectoryPoint(positions=(desired - actual).tolist())
        return msg


class ExecuteTrajectoryShape(ActionShape):
    """arm_sim_node's own action: the result also says how the arm followed (tracking, overrun, contacts)."""

    def __init__(self) -> None:
        super().__init__(ExecuteTrajectory)

    def refused(self, code: int, message: str) -> Any:
        return ExecuteTrajectory.Result(error_code=code, error_string=one_line(message), overrun=-1.0)

    def finished(self, code: int, message: str, result: ExecutionResult) -> Any:
        return ExecuteTrajectory.Result(
            error_code=code,
            error_string=one_line(message),
            max_tracking_error=float(np.max(result.max_error)) if len(result.times) else 0.0,
            overrun=-1.0 if result.overrun is None else float(result.overrun),
            contact_links=[c.link for c in result.contacts],
            contact_obstacles=[c.obstacle for c in result.contacts],
            contact_depths=[float(c.depth) for c in result.contacts],
            saturated_steps=int(result.saturated_steps),
        )


class FollowJointTrajectoryShape(ActionShape):
    """control_msgs/action/FollowJointTrajectory: error code and string; multi-DOF goals refused."""

    def check(self, request: Any) -> None:
        multi_dof = list(request.multi_dof_trajectory.joint_names) or [
            t.joint_name for t in (*request.component_path_tolerance, *request.component_goal_tolerance)
        ]
        if multi_dof or request.multi_dof_trajectory.points:
            raise InvalidJointNames(
                f"multi-DOF joints {sorted(set(multi_dof))}: this arm has only revolute and prismatic joints"
            )
