"""Dual-arm coordination for Maru-1: both hands keep their relative pose (one object carried with two hands)
while the waist and both arms move -- paper 000's 13-DOF upper body under a closed-chain constraint.

:data:`DUAL_CARRY` is the named example problem: the hands hold an object in front of the robot at the
start; at the goal the waist has turned by 1 rad and the arms have lifted and tilted the object, in the
desk-and-box scene. The hands' relative pose (``l_hand`` in ``r_hand``'s frame) is held within 1 mm per
translation component (so <= 1.7 mm in distance) and 0.01 rad per rotation component all along
(:class:`~maru_planner.planning.constraints.RelativePoseConstraint`), planned by CBiRRT.
``python -m maru_planner.planning.dual_arm out.png`` plans it and draws the hand traces.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maru_planner.paths import config_path
from maru_planner.planning.constraints import PathConstraints, RelativePoseConstraint
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.types import MotionRequest
from maru_planner.robot import RobotModel
from maru_planner.scene import Scene


@dataclass(frozen=True)
class DualArmProblem:
    name: str
    scene_file: str
    group: str
    start: tuple[float, ...]  # upper_body order: waist, right arm 1-6, left arm 1-6
    goal: tuple[float, ...]
    position_tolerance: float  # m
    orientation_tolerance: float  # rad
    description: str

    def scene(self) -> Scene:
        return Scene.from_yaml(config_path("scenes", self.scene_file))

    def constraints(self, robot) -> PathConstraints:
        """The hands' relative pose at the start, to be kept."""
        held = RelativePoseConstraint.held(
            robot, np.asarray(self.start), "r_hand", "l_hand",
            position_tolerance=self.position_tolerance, orientation_tolerance=self.orientation_tolerance,
        )  # fmt: skip
        return PathConstraints(relative=held)

    def request(self, robot, *, seed: int | None = None, time_budget: float = 20.0) -> MotionRequest:
        names = robot.groups[self.group]
        return MotionRequest(
            self.group, start=dict(zip(names, self.start, strict=True)),
            goal_joints=dict(zip(names, self.goal, strict=True)), planner_id="CBiRRT", seed=seed,
            time_budget=time_budget, path_constraints=self.constraints(robot),
        )  # fmt: skip


DUAL_CARRY = DualArmProblem(
    name="maru13_dual_carry",
    scene_file="maru13_desk_box.yaml",
    group="upper_body",
    start=(-0.5, 0.3141, 1.769, 0.2167, 0.9715, -0.523, -1.2391, 0.0156, 2.6995, 2.3236, 1.2897, -2.8949, -0.4105),
    goal=(
        0.5,
        0.52521189,
        1.70682564,
        0.06152298,
        1.07621425,
        -0.2792433,
        -1.33254688,
        0.18268811,
        2.73834052,
        2.46982802,
        1.31932287,
        -2.99810625,
        -0.38257917,
    ),  # fmt: skip
    position_tolerance=1e-3,
    orientation_tolerance=1e-2,
    description="13-DOF: both hands carry one object (relative pose held to 1 mm / 0.01 rad) while the waist "
    "turns 1 rad and the arms lift it",
)


def relative_pose_error(robot, problem: DualArmProblem, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per trajectory sample (rows: ``problem.group`` joints): the hands' relative-pose error from the start's,
    as (translation error in m, rotation error in rad) -- measured directly, not through the constraint."""
    q = np.asarray(robot.neutral(), dtype=float)
    indices = robot.group_joint_indices(problem.group)
    q[indices] = problem.start
    held = np.linalg.solve(robot.frame_pose(q, "r_hand").copy(), robot.frame_pose(q, "l_hand"))
    translation, rotation = [], []
    for row in np.atleast_2d(positions):
        q[indices] = row
        now = np.linalg.solve(robot.frame_pose(q, "r_hand").copy(), robot.frame_pose(q, "l_hand"))
        translation.append(np.linalg.norm(now[:3, 3] - held[:3, 3]))
        cos = (np.trace(held[:3, :3].T @ now[:3, :3]) - 1.0) / 2.0
        rotation.append(np.arccos(np.clip(cos, -1.0, 1.0)))
    return np.array(translation), np.array(rotation)


def main(argv: list[str] | None = None) -> int:
    """Plan :data:`DUAL_CARRY` (seed 1) and draw it to ``argv[0]`` (default docs/img/dual_arm_carry.png)."""
    from maru_planner.viz.plans import plot_plan  # lazy: matplotlib only for the picture

    out = Path((argv or sys.argv[1:] or ["docs/img/dual_arm_carry.png"])[0])
    robot = RobotModel.maru1()
    scene = DUAL_CARRY.scene()
    result = MotionPlanner.from_scene(robot, scene).plan(DUAL_CARRY.request(robot, seed=1))
    if not result.success or result.trajectory is None:
        print(f"{DUAL_CARRY.name}: {result.status.value}: {result.message}", file=sys.stderr)
        return 1
    translation, rotation = relative_pose_error(robot, DUAL_CARRY, result.trajectory.positions)
    title = (f"{DUAL_CARRY.name}: CBiRRT, hands' relative pose error <= {translation.max() * 1e3:.2f} mm, "
             f"{rotation.max():.4f} rad")  # fmt: skip
    plot_plan(robot, scene, result, out, title=title)
    print(f"{title}; picture {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
