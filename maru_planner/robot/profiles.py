"""Robot profiles, one table: the robots the package knows by name.

Each robot is one module of ``maru_planner/robot/robots/`` with its :class:`RobotProfile` (what a
profile says: :mod:`maru_planner.robot.robot_profile`, as the module's ``PROFILE``); this module finds and
registers every one of them, in module-name order. Adding a robot is one module there;
``RobotModel.from_profile(name)`` loads it.

Robots from the example-robot-data wheel (no Python module: URDF/SRDF/meshes live under
``<prefix>/share/example-robot-data/robots``, meshes referenced as ``package://example-robot-data/...``
so ``<prefix>/share`` is the package dir): Panda, UR5, TIAGo and Talos (their modules say how their
non-planning joints are treated, nq == nv for planning).
"""

from __future__ import annotations

import pkgutil
from importlib import import_module

from maru_planner.robot import robots
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

KNOWN_ROBOTS: tuple[RobotProfile, ...] = tuple(
    import_module(f"{robots.__name__}.{module.name}").PROFILE
    for module in sorted(pkgutil.iter_modules(robots.__path__), key=lambda m: m.name)
)

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
