"""What a robot profile is, and the table of profiles that ``RobotModel.from_profile(name)`` reads.

A :class:`RobotProfile` says where a robot's URDF/SRDF are, its acceleration limits (URDF has no
field for them), end effectors, planning groups to add to the SRDF's, joints to lock, whether links
touching at rest are to be ignored (MoveIt's "Default" rule for robots shipped without an SRDF), the
options of its sphere model's fit, and its IK strategies (tried before the numeric IK, see
:mod:`maru_planner.robot.ik`). Profiles are written as YAML files (:mod:`maru_planner.robot.profile_yaml`,
docs/your_robot.md).

This module only holds the (generic) table; the built-in robots live in ``maru_planner/robot/robots/``
(``<name>.yaml``, and a module where a robot has code of its own) and :mod:`maru_planner.robot.profiles`
registers them (importing ``maru_planner.robot`` does, so the table is full whenever a robot module is in use).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from maru_planner.errors import InvalidRequest
from maru_planner.paths import urdf_path
from maru_planner.robot.ik_strategy import IKStrategy
from maru_planner.robot.sphere_options import SphereFitOptions

DEFAULT_ACCELERATION_LIMIT = 4.0  # rad/s^2 (or m/s^2): URDF has no field for it


class InvalidRobotProfile(InvalidRequest):
    """A robot profile (a YAML file or its fields) that cannot be used; the message names the file and field."""

    source = "robot"


@dataclass(frozen=True)
class RobotFiles:
    urdf: Path
    srdf: Path | None
    package_dirs: list[Path]


@dataclass(frozen=True)
class RobotProfile:
    """One robot: files, limits, end effectors, extra groups, collision rule, sphere-model options and IK."""

    name: str
    source: str  # a key of SOURCES, or a directory: where ``urdf`` and ``srdf`` are relative to
    urdf: str
    srdf: str | None = None
    urdf_name: str = ""  # the URDF's <robot name>: a model loaded from the files by path gets this profile too
    acceleration_limits: float | tuple[float, ...] = DEFAULT_ACCELERATION_LIMIT
    end_effectors: dict[str, str] = field(default_factory=dict)  # empty: the SRDF's
    groups: dict[str, list[str]] = field(default_factory=dict)  # added to the SRDF's (same name: replaces it)
    ignore_links_touching_at_rest: bool = False
    ik_strategies: tuple[IKStrategy, ...] = ()
    package_dirs: tuple[str, ...] = ()  # more directories where package:// mesh URIs resolve
    locked_joints: dict[str, float] = field(default_factory=dict)  # joint -> the value it is frozen at
    sphere_model: SphereFitOptions = field(default_factory=SphereFitOptions)  # how its sphere model is fitted

    def files(self) -> RobotFiles:
        source = SOURCES.get(self.source)
        root, package_dirs = source() if source is not None else (Path(self.source), [])
        extra = [Path(d) for d in self.package_dirs]
        return RobotFiles(root / self.urdf, root / self.srdf if self.srdf else None, [*package_dirs, *extra])


def example_robot_data_dir() -> Path:
    """``<prefix>/share/example-robot-data/robots`` of the installed wheel."""
    candidates = [Path(sys.prefix), *(Path(p) for p in sys.path if p.endswith("site-packages"))]
    for base in candidates:
        for robots in (
            base / "share/example-robot-data/robots",
            base / "cmeel.prefix/share/example-robot-data/robots",
            *base.glob("lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots"),
        ):
            if robots.is_dir():
                return robots
    raise FileNotFoundError("example-robot-data share directory not found (pip install example-robot-data)")


def _example_robot_data() -> tuple[Path, list[Path]]:
    robots = example_robot_data_dir()
    return robots, [robots.parent.parent]  # package://example-robot-data/... resolves below <prefix>/share


def _package_urdf() -> tuple[Path, list[Path]]:
    return urdf_path(), []


SOURCES: dict[str, Callable[[], tuple[Path, list[Path]]]] = {
    "maru_planner": _package_urdf,
    "example-robot-data": _example_robot_data,
}

PROFILES: dict[str, RobotProfile] = {}  # filled by maru_planner.robot.profiles


def register(robot: RobotProfile) -> None:
    """Add (or replace) a robot of the table."""
    PROFILES[robot.name] = robot


def profile(name: str) -> RobotProfile:
    """The profile called ``name``; InvalidRequest listing the known robots otherwise."""
    found = PROFILES.get(name)
    if found is None:
        raise InvalidRequest(f"unknown robot {name!r}; known: {sorted(PROFILES)}")
    return found


def profile_for_urdf(urdf_name: str) -> RobotProfile | None:
    """The profile whose URDF has ``<robot name="urdf_name">``, if any."""
    return next((p for p in PROFILES.values() if p.urdf_name and p.urdf_name == urdf_name), None)
