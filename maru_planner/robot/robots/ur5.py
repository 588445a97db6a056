"""Universal Robots UR5 (example-robot-data): its profile is ``ur5.yaml`` (which adds the planning group its SRDF
lacks)."""

from __future__ import annotations

from pathlib import Path

from maru_planner.robot.profile_yaml import load_profile

PROFILE = load_profile(Path(__file__).with_suffix(".yaml"), check_files=False)
UR5_JOINTS = list(PROFILE.groups["manipulator"])
