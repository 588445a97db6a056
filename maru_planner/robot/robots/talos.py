"""PAL Talos (example-robot-data), reduced model: its profile is ``talos.yaml``."""

from __future__ import annotations

from pathlib import Path

from maru_planner.robot.profile_yaml import load_profile

PROFILE = load_profile(Path(__file__).with_suffix(".yaml"), check_files=False)
