"""Robots from the example-robot-data wheel (Panda, UR5, TIAGo, Talos).

The wheel has no Python module: its URDF/SRDF/meshes live under
``<prefix>/share/example-robot-data/robots``; meshes are referenced as
``package://example-robot-data/...`` so ``<prefix>/share`` is the package dir.

Treatment of non-planning joints (so that nq == nv for the planning API):
- TIAGo: the no-hand model; the wheels (continuous joints) are locked at 0,
  i.e. the base is fixed; planning uses torso lift, head and the 7-DOF arm.
  It ships without an SRDF: parent/child links and the link pairs touching at
  the neutral posture (MoveIt's "Default" rule) are not checked.
- Talos: loaded with a fixed base (no free-flyer), all 32 revolute joints
  kept; SRDF groups (r_arm, l_arm, torso, ...) select the planned subset.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

from maru_planner.errors import InvalidRequest
from maru_planner.robot.model import RobotModel


@dataclass(frozen=True)
class ExampleRobot:
    urdf: str
    srdf: str | None
    end_effectors: dict[str, str]
    acceleration_limits: float | tuple[float, ...] = 4.0
    groups: dict[str, list[str]] = field(default_factory=dict)  # added when the SRDF has none


PANDA_ACCEL = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0, 1.0, 1.0)  # Franka datasheet (+ fingers)
UR5_JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]
TIAGO_ARM = [f"arm_{i}_joint" for i in range(1, 8)]

EXAMPLE_ROBOTS: dict[str, ExampleRobot] = {
    "panda": ExampleRobot(
        "panda_description/urdf/panda.urdf",
        "panda_description/srdf/panda.srdf",
        {"hand": "panda_hand_tcp"},
        PANDA_ACCEL,
    ),
    "ur5": ExampleRobot(
        "ur_description/urdf/ur5_robot.urdf",
        "ur_description/srdf/ur5.srdf",
        {"tool": "tool0"},
        3.0,
        {"manipulator": UR5_JOINTS},
    ),
    "tiago": ExampleRobot(
        "tiago_description/robots/tiago_no_hand.urdf",
        None,
        {"tool": "arm_tool_link"},
        2.0,
        {"arm": TIAGO_ARM, "arm_torso": ["torso_lift_joint", *TIAGO_ARM]},
    ),
    "talos": ExampleRobot(
        "talos_data/robots/talos_reduced.urdf",
        "talos_data/srdf/talos.srdf",
        {"right": "gripper_right_base_link", "left": "gripper_left_base_link"},
        4.0,
    ),
}


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


def load_example_robot(name: str) -> RobotModel:
    """Load 'panda', 'ur5', 'tiago' or 'talos' from example-robot-data."""
    spec = EXAMPLE_ROBOTS.get(name)
    if spec is None:
        raise InvalidRequest(f"unknown example robot {name!r}; known: {sorted(EXAMPLE_ROBOTS)}")
    robots = example_robot_data_dir()
    share = robots.parent.parent  # package://example-robot-data/... resolves below <prefix>/share
    robot = RobotModel.from_urdf(
        robots / spec.urdf,
        robots / spec.srdf if spec.srdf else None,
        package_dirs=[share],
        name=name,
        acceleration_limits=spec.acceleration_limits,
        end_effectors=spec.end_effectors,
    )
    if spec.groups and set(robot.groups) == {"all"}:
        robot.groups = {"all": robot.groups["all"], **spec.groups}
    if spec.srdf is None:
        robot.disable_default_collisions()  # no SRDF: links touching at rest are not checked
    return robot
