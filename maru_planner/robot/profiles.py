"""Robot profiles, one table: the robots the package knows by name.

Each robot is one profile file ``maru_planner/robot/robots/<name>.yaml`` (what a profile says:
:mod:`maru_planner.robot.robot_profile`, the file's keys: :mod:`maru_planner.robot.profile_yaml`), with a module
of the same name when the robot has code or public names of its own (its ``PROFILE`` is read from the file);
this module finds and registers every one of them, in file-name order. Adding a robot is one YAML file there;
``RobotModel.from_profile(name)`` loads it. A robot outside the package needs no entry here: its file is
loaded by path (``RobotModel.from_profile("my_arm.yaml")``, ``maru-plan --robot my_arm.yaml``).

Robots from the example-robot-data wheel (no Python module: URDF/SRDF/meshes live under
``<prefix>/share/example-robot-data/robots``, meshes referenced as ``package://example-robot-data/...``
so ``<prefix>/share`` is the package dir): Panda, UR5, TIAGo and Talos (their modules say how their
non-planning joints are treated, nq == nv for planning).
"""

from __future__ import annotations

import pkgutil
from importlib import import_module
from pathlib import Path

from maru_planner.robot import robots
from maru_planner.robot.profile_yaml import load_profile
from maru_planner.robot.robot_profile import (
    DEFAULT_ACCELERATION_LIMIT,
    PROFILES,
    SOURCES,
    RobotFiles,
    RobotProfile,
    example_robot_data_dir,
    profile,
    profile_for_urdf,
    register,
)
from maru_planner.robot.robots.tiago import TIAGO_ARM
from maru_planner.robot.robots.ur5 import UR5_JOINTS


def built_in_profiles() -> tuple[RobotProfile, ...]:
    """Every robot of ``robots/``: a module's ``PROFILE``, else the YAML file alone (file-name order)."""
    modules = {m.name for m in pkgutil.iter_modules(robots.__path__)}
    files = {p.stem: p for folder in robots.__path__ for p in Path(folder).glob("*.yaml")}
    return tuple(
        import_module(f"{robots.__name__}.{name}").PROFILE
        if name in modules
        else load_profile(files[name], check_files=False)
        for name in sorted(modules | set(files))
    )


KNOWN_ROBOTS: tuple[RobotProfile, ...] = built_in_profiles()

for _robot in KNOWN_ROBOTS:
    register(_robot)

__all__ = [
    "DEFAULT_ACCELERATION_LIMIT",
    "KNOWN_ROBOTS",
    "PROFILES",
    "SOURCES",
    "TIAGO_ARM",
    "UR5_JOINTS",
    "RobotFiles",
    "RobotProfile",
    "example_robot_data_dir",
    "profile",
    "profile_for_urdf",
    "register",
]
