"""PAL TIAGo (example-robot-data), the no-hand model.

The wheels (continuous joints) are locked at 0, i.e. the base is fixed; planning uses torso lift, head
and the 7-DOF arm. It ships without an SRDF: parent/child links and the link pairs touching at the
neutral posture are not checked.
"""

from __future__ import annotations

from maru_planner.robot.robot_profile import RobotProfile

TIAGO_ARM = [f"arm_{i}_joint" for i in range(1, 8)]

PROFILE = RobotProfile(
    "tiago",
    "example-robot-data",
    "tiago_description/robots/tiago_no_hand.urdf",
    acceleration_limits=2.0,
    end_effectors={"tool": "arm_tool_link"},
    groups={"arm": TIAGO_ARM, "arm_torso": ["torso_lift_joint", *TIAGO_ARM]},
    ignore_links_touching_at_rest=True,
)
