"""Universal Robots UR5 (example-robot-data); its SRDF has no planning group, so the profile adds one."""

from __future__ import annotations

from maru_planner.robot.robot_profile import RobotProfile

UR5_JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]

PROFILE = RobotProfile(
    "ur5",
    "example-robot-data",
    "ur_description/urdf/ur5_robot.urdf",
    "ur_description/srdf/ur5.srdf",
    acceleration_limits=3.0,
    end_effectors={"tool": "tool0"},
    groups={"manipulator": UR5_JOINTS},
)
