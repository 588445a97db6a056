"""Old home of the robot carrying attached objects, now :mod:`maru_planner.robot.attached` (re-exported here)."""

from maru_planner.robot.attached import (
    CarryingRobot,
    attachment_key,
    base_robot,
    check_attachments,
    robot_with_attached,
)

__all__ = ["CarryingRobot", "attachment_key", "base_robot", "check_attachments", "robot_with_attached"]
