"""Old home of Maru-1's IK strategies, now in :mod:`maru_planner.robot.robots.maru1` (re-exported here)."""

from maru_planner.robot.robots.maru1 import (
    ARM_GROUPS,
    BOTH_HANDS_GROUP,
    arm_ik_closed_form,
    one_arm_strategy,
    two_hand_ik,
    two_hands_strategy,
    waist_angle_from_hands,
)

__all__ = [
    "ARM_GROUPS",
    "BOTH_HANDS_GROUP",
    "arm_ik_closed_form",
    "one_arm_strategy",
    "two_hand_ik",
    "two_hands_strategy",
    "waist_angle_from_hands",
]
