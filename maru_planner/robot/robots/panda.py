"""Franka Emika Panda (example-robot-data): its profile is ``panda.yaml``; here the finger opening
MotionBenchMaker's problems use."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from maru_planner.robot.model import RobotModel
from maru_planner.robot.profile_yaml import load_profile

PROFILE = load_profile(Path(__file__).with_suffix(".yaml"), check_files=False)

PANDA_FINGERS_OPEN = {"panda_finger_joint1": 0.065, "panda_finger_joint2": 0.065}  # MotionBenchMaker's convention


def mbm_panda() -> RobotModel:
    """example-robot-data's Panda with its finger limits (0.04 m) widened to :data:`PANDA_FINGERS_OPEN`, the
    MotionBenchMaker problems' finger opening."""
    robot = RobotModel.from_profile(PROFILE)
    fingers = robot.joint_indices(list(PANDA_FINGERS_OPEN))
    robot.upper_limits[fingers] = np.maximum(robot.upper_limits[fingers], list(PANDA_FINGERS_OPEN.values()))
    return robot
