"""Franka Emika Panda (example-robot-data), and the finger opening MotionBenchMaker's problems use."""

from __future__ import annotations

import numpy as np

from maru_planner.robot.model import RobotModel
from maru_planner.robot.robot_profile import RobotProfile

PROFILE = RobotProfile(
    "panda",
    "example-robot-data",
    "panda_description/urdf/panda.urdf",
    "panda_description/srdf/panda.srdf",
    acceleration_limits=(15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0, 1.0, 1.0),  # Franka datasheet (+ fingers)
    end_effectors={"hand": "panda_hand_tcp"},
)

PANDA_FINGERS_OPEN = {"panda_finger_joint1": 0.065, "panda_finger_joint2": 0.065}  # MotionBenchMaker's convention


def mbm_panda() -> RobotModel:
    """example-robot-data's Panda with its finger limits (0.04 m) widened to :data:`PANDA_FINGERS_OPEN`, the
    MotionBenchMaker problems' finger opening."""
    robot = RobotModel.from_profile(PROFILE)
    fingers = robot.joint_indices(list(PANDA_FINGERS_OPEN))
    robot.upper_limits[fingers] = np.maximum(robot.upper_limits[fingers], list(PANDA_FINGERS_OPEN.values()))
    return robot
