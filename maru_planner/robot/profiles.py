"""Robot profiles, one table: what is particular to each robot the package knows by name.

A :class:`RobotProfile` says where a robot's URDF/SRDF are, its acceleration limits (URDF has no
field for them), end effectors, planning groups to add when it has no SRDF, whether links touching
at rest are to be ignored (MoveIt's "Default" rule for robots shipped without an SRDF), and its IK
strategies (tried before the numeric IK, see :mod:`maru_planner.robot.ik`). Adding a robot is one
entry in :data:`PROFILES`; ``RobotModel.from_profile(name)`` loads it.

Robots from the example-robot-data wheel (no Python module: URDF/SRDF/meshes live under
``<prefix>/share/example-robot-data/robots``, meshes referenced as ``package://example-robot-data/...``
so ``<prefix>/share`` is the package dir). Treatment of non-planning joints (nq == nv for planning):

- TIAGo: the no-hand model; the wheels (continuous joints) are locked at 0, i.e. the base is fixed;
  planning uses torso lift, head and the 7-DOF arm. It ships without an SRDF: parent/child links and
  the link pairs touching at the neutral posture are not checked.
- Talos: loaded with a fixed base (no free-flyer), all 32 revolute joints kept; SRDF groups
  (r_arm, l_arm, torso, ...) select the planned subset.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from maru_planner.errors import InvalidRequest
from maru_planner.paths import urdf_path
from maru_planner.robot import maru1_description, maru1_ik
from maru_planner.robot.ik import IKStrategy

DEFAULT_ACCELERATION_LIMIT = 4.0  # rad/s^2 (or m/s^2): URDF has no field for it


@dataclass(frozen=True)
class RobotFiles:
    urdf: Path
    srdf: Path | None
    package_dirs: list[Path]


@dataclass(frozen=True)
class RobotProfile:
    """One robot: files, limits, end effectors, extra groups, collision rule and IK strategies."""

    name: str
    source: str  # a key of SOURCES: where ``urdf`` and ``srdf`` are relative to
    urdf: str
    srdf: str | None = None
    urdf_name: str = ""  # the URDF's <robot name>: a model loaded from the files by path gets this profile too
    acceleration_limits: float | tuple[float, ...] = DEFAULT_ACCELERATION_LIMIT
    end_effectors: dict[str, str] = field(default_factory=dict)  # empty: the SRDF's
    groups: dict[str, list[str]] = field(default_factory=dict)  # added when the SRDF has none
    ignore_links_touching_at_rest: bool = False
    ik_strategies: tuple[IKStrategy, ...] = ()

    def files(self) -> RobotFiles:
        root, package_dirs = SOURCES[self.source]()
        return RobotFiles(root / self.urdf, root / self.srdf if self.srdf else None, package_dirs)


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

UR5_JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]
TIAGO_ARM = [f"arm_{i}_joint" for i in range(1, 8)]

PROFILES: dict[str, RobotProfile] = {
    "maru1": RobotProfile(
        "maru1",
        "maru_planner",
        "maru1_upper_body.urdf",
        "maru1_upper_body.srdf",
        urdf_name="maru1_upper_body",
        acceleration_limits=maru1_description.ACCELERATION_LIMIT,
        ik_strategies=(maru1_ik.one_arm_strategy, maru1_ik.two_hands_strategy),
    ),
    "panda": RobotProfile(
        "panda",
        "example-robot-data",
        "panda_description/urdf/panda.urdf",
        "panda_description/srdf/panda.srdf",
        acceleration_limits=(15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0, 1.0, 1.0),  # Franka datasheet (+ fingers)
        end_effectors={"hand": "panda_hand_tcp"},
    ),
    "ur5": RobotProfile(
        "ur5",
        "example-robot-data",
        "ur_description/urdf/ur5_robot.urdf",
        "ur_description/srdf/ur5.srdf",
        acceleration_limits=3.0,
        end_effectors={"tool": "tool0"},
        groups={"manipulator": UR5_JOINTS},
    ),
    "tiago": RobotProfile(
        "tiago",
        "example-robot-data",
        "tiago_description/robots/tiago_no_hand.urdf",
        acceleration_limits=2.0,
        end_effectors={"tool": "arm_tool_link"},
        groups={"arm": TIAGO_ARM, "arm_torso": ["torso_lift_joint", *TIAGO_ARM]},
        ignore_links_touching_at_rest=True,
    ),
    "talos": RobotProfile(
        "talos",
        "example-robot-data",
        "talos_data/robots/talos_reduced.urdf",
        "talos_data/srdf/talos.srdf",
        end_effectors={"right": "gripper_right_base_link", "left": "gripper_left_base_link"},
    ),
}


def profile(name: str) -> RobotProfile:
    """The profile called ``name``; InvalidRequest listing the known robots otherwise."""
    found = PROFILES.get(name)
    if found is None:
        raise InvalidRequest(f"unknown robot {name!r}; known: {sorted(PROFILES)}")
    return found


def profile_for_urdf(urdf_name: str) -> RobotProfile | None:
    """The profile whose URDF has ``<robot name="urdf_name">``, if any."""
    return next((p for p in PROFILES.values() if p.urdf_name and p.urdf_name == urdf_name), None)
