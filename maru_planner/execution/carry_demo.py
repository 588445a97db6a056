"""The demo that moves something: Maru-1 carries a box with both hands from the right of the desk to the left.

    python -m maru_planner.execution.carry_demo [--out docs/images/execution_carry.png] [--seed 1]

The box (:data:`BOX_SIZE`) is attached to ``r_hand`` between the hands (the wrists and hands touch it), on the desk
of the paper-000 scene (its standing box removed: this one is carried instead). The motion is the dual-arm carry of
:data:`~maru_planner.planning.dual_arm.DUAL_CARRY` (the hands' relative pose held to 1 mm / 0.01 rad by CBiRRT; the
arms lift and tilt the box) with the waist turning from :data:`START_WAIST` to :data:`GOAL_WAIST`. It is planned by
:class:`~maru_planner.planning.MotionPlanner` with the box as an attached body, then executed on the MuJoCo arm
(:mod:`maru_planner.physics.arm_model`; the box, :data:`BOX_MASS`, a body welded to the right hand: the
simulation has no closed chains) by :class:`ArmController` like
joint_trajectory_controller would. Prints the tracking error, contacts, overrun and how well the *executed* motion
kept the hands' grip (the relative-pose error of the simulated arm), and draws the executed motion.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maru_planner.execution.executor import ArmController, ExecutionResult
from maru_planner.execution.interpolation import checked_points
from maru_planner.physics.arm_model import ServoGains, build_arm_model
from maru_planner.physics.arm_sim import ArmSim
from maru_planner.planning import MotionPlanner
from maru_planner.planning.dual_arm import DUAL_CARRY, DualArmProblem, relative_pose_error
from maru_planner.planning.types import MotionResult
from maru_planner.robot import RobotModel
from maru_planner.scene import Scene
from maru_planner.scene.obstacle import Obstacle

BOX = "carried_box"
BOX_SIZE = (0.26, 0.12, 0.12)  # m: along the hands' axis, across, up
BOX_MASS = 1.0  # kg: carried by the right hand's servos in the simulation (a closed chain is not simulated)
GRIP_LINKS = ("r_hand", "l_hand", "r_arm_link5", "l_arm_link5")  # touch the box without colliding
START_WAIST, GOAL_WAIST = -1.3, 0.3  # rad: the box over the desk's right part, then its left part
DEFAULT_OUT = Path("docs/images/execution_carry.png")


@dataclass
class CarryRun:
    """One planned and executed carry: the problem, the scene with the box attached, the plan and its execution."""

    robot: RobotModel
    problem: DualArmProblem
    scene: Scene
    plan: MotionResult
    execution: ExecutionResult | None

    def q_full(self, row: np.ndarray) -> np.ndarray:
        """The robot's full configuration with the group at ``row``."""
        q = np.asarray(self.robot.neutral(), dtype=float)
        q[self.robot.group_joint_indices(self.problem.group)] = row
        return q

    def grip_error(self, positions: np.ndarray) -> tuple[float, float]:
        """Largest hands' relative-pose error (m, rad) from the start's along ``positions`` (group rows)."""
        translation, rotation = relative_pose_error(self.robot, self.problem, positions)
        return float(translation.max()), float(rotation.max())


def carry_problem() -> DualArmProblem:
    """:data:`DUAL_CARRY` with the waist turning from :data:`START_WAIST` to :data:`GOAL_WAIST`."""
    start, goal = list(DUAL_CARRY.start), list(DUAL_CARRY.goal)
    start[0], goal[0] = START_WAIST, GOAL_WAIST
    return dataclasses.replace(
        DUAL_CARRY,
        name="maru13_box_carry",
        start=tuple(start),
        goal=tuple(goal),
        description="13-DOF: both hands carry a box from the right of the desk to the left",
    )


def carry_scene(robot: RobotModel, problem: DualArmProblem) -> Scene:
    """The desk, and the box attached to ``r_hand`` midway between the hands at the start, along their axis."""
    scene = problem.scene()
    scene.remove("box")
    q = np.asarray(robot.neutral(), dtype=float)
    q[robot.group_joint_indices(problem.group)] = problem.start
    right, left = robot.frame_pose(q, "r_hand"), robot.frame_pose(q, "l_hand")
    along = left[:3, 3] - right[:3, 3]
    along /= np.linalg.norm(along)
    up = np.array([0.0, 0.0, 1.0]) - along * along[2]
    up /= np.linalg.norm(up)
    box = np.eye(4)
    box[:3, :3] = np.column_stack([along, np.cross(up, along), up])
    box[:3, 3] = (right[:3, 3] + left[:3, 3]) / 2.0
    obstacle = Obstacle(BOX, "box", np.linalg.solve(right, box), size=list(BOX_SIZE))
    scene.attach(BOX, "r_hand", obstacle=obstacle, touch_links=list(GRIP_LINKS))
    return scene


def run_carry(seed: int = 1, gains: ServoGains | None = None) -> CarryRun:
    """Plan the carry (CBiRRT, seed ``seed``) and, if it succeeds, execute it on the simulated arm."""
    robot = RobotModel.maru1()
    problem = carry_problem()
    scene = carry_scene(robot, problem)
    plan = MotionPlanner.from_scene(robot, scene).plan(problem.request(robot, seed=seed))
    run = CarryRun(robot, problem, scene, plan, None)
    if not plan.success or plan.trajectory is None:
        return run
    q0 = run.q_full(np.asarray(problem.start))
    sim = ArmSim(build_arm_model(robot, scene, gains or ServoGains(), q0=q0, payloads={BOX: BOX_MASS}))
    sim.reset(q0)
    tr = plan.trajectory
    points = checked_points(tr.joint_names, tr.times, tr.positions, tr.velocities, tr.accelerations)
    run.execution = ArmController(sim).run(points)
    return run


def summary(run: CarryRun) -> str:
    """One line: the plan, the execution's outcome, tracking error, contacts, overrun and grip errors."""
    if run.execution is None:
        return f"{run.problem.name}: not planned: {run.plan.status.value}: {run.plan.message}"
    result, tr = run.execution, run.plan.trajectory
    assert tr is not None
    planned, executed = run.grip_error(tr.positions), run.grip_error(result.actual)
    overrun = "never reached" if result.overrun is None else f"{100 * result.overrun:.2f} %"
    waypoints = 0 if run.plan.path is None else len(run.plan.path)
    return (
        f"{run.problem.name}: planned {tr.duration:.2f} s ({waypoints} waypoints); executed: "
        f"{result.code.name}, max tracking error {result.max_error.max():.4f} rad, {len(result.contacts)} contacts, "
        f"overrun {overrun}, {result.saturated_steps} saturated steps; hands' relative pose held to "
        f"{1e3 * planned[0]:.2f} mm / {planned[1]:.4f} rad planned, {1e3 * executed[0]:.2f} mm / "
        f"{executed[1]:.4f} rad executed"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the picture (PNG)")
    parser.add_argument("--seed", type=int, default=1, help="the planner's seed")
    args = parser.parse_args(argv)
    run = run_carry(args.seed)
    print(summary(run))
    if run.execution is None:
        return 1
    from maru_planner.execution.carry_picture import draw_carry  # lazy: matplotlib only for the picture

    print(f"picture {draw_carry(run, args.out)}")
    return 0 if run.execution.success and not run.execution.contacts else 1


if __name__ == "__main__":
    sys.exit(main())
