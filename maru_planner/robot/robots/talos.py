"""PAL Talos (example-robot-data), reduced model.

Loaded with a fixed base (no free-flyer), all 32 revolute joints kept; SRDF groups (r_arm, l_arm,
torso, ...) select the planned subset.
"""

from __future__ import annotations

from maru_planner.robot.robot_profile import RobotProfile

PROFILE = RobotProfile(
    "talos",
    "example-robot-data",
    "talos_data/robots/talos_reduced.urdf",
    "talos_data/srdf/talos.srdf",
    end_effectors={"right": "gripper_right_base_link", "left": "gripper_left_base_link"},
)
