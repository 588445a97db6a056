"""Paper 000's two reference problems (its "Experiments"; see docs/planning.md) by name.

13-DOF values are in the order (waist, right arm 1–6, left arm 1–6) = the ``upper_body`` group
order of the Maru-1 SRDF; the 6-DOF problem is the right arm with the rest at neutral.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from maru_planner.paths import config_path


@dataclass(frozen=True)
class Problem:
    name: str
    robot: str
    scene_file: str
    group: str
    start: tuple[float, ...]
    goal: tuple[float, ...]
    description: str

    @property
    def scene_path(self) -> Path:
        return config_path("scenes", self.scene_file)

    def start_dict(self, joint_names) -> dict[str, float]:
        return dict(zip(joint_names, self.start, strict=True))

    def goal_dict(self, joint_names) -> dict[str, float]:
        return dict(zip(joint_names, self.goal, strict=True))


PROBLEMS = {
    "maru6": Problem(
        name="maru6",
        robot="maru1",
        scene_file="maru6_desk.yaml",
        group="right_arm",
        start=(0.0, 1.57, 1.57, 0.0, -1.57, -1.57),
        goal=(-1.57, 1.57, 1.57, 0.0, -1.57, -1.57),
        description="6-DOF right arm: from stretched forward over the desk, avoid it and lower the arm",
    ),
    "maru13": Problem(
        name="maru13",
        robot="maru1",
        scene_file="maru13_desk_box.yaml",
        group="upper_body",
        start=(-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25),
        goal=(0.9, -0.8, 1.57, 1.14, 0.7, -1.24, -1.9, -0.7, 1.57, 2.44, 0.7, -2.24, -1.25),
        description="13-DOF upper body: both arms from the right of the box, around it, to the left",
    ),
}
