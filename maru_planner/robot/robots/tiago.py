"""PAL TIAGo (example-robot-data), the no-hand model: its profile is ``tiago.yaml`` (wheels locked, no SRDF)."""

from __future__ import annotations

from pathlib import Path

from maru_planner.robot.profile_yaml import load_profile

PROFILE = load_profile(Path(__file__).with_suffix(".yaml"), check_files=False)
TIAGO_ARM = list(PROFILE.groups["arm"])
