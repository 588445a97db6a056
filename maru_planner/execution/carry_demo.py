"""The demo that moves something: Maru-1 carries a box with both hands from the right of the desk to the left.

    python -m maru_planner.execution.carry_demo [--out docs/images/execution_carry.png] [--seed 1]
    python -m maru_planner.execution.carry_demo --through-ros [--out PNG] [--seed 1]

The box (:data:`BOX_SIZE`) is attached to ``r_hand`` between the hands (the wrists and hands touch it), on the desk
of the paper-000 scene (its standing box removed: this one is carried instead). The motion is the dual-arm carry of
:data:`~maru_planner.planning.dual_arm.DUAL_CARRY` (the hands' relative pose held to 1 mm / 0.01 rad by CBiRRT; the
arms lift and tilt the box) with the waist turning from :data:`START_WAIST` to :data:`GOAL_WAIST`. It is planned by
:class:`~maru_planner.planning.MotionPlanner` with the box as an attached body, then executed on the MuJoCo arm
(:mod:`maru_planner.physics.arm_model`; the box, :data:`BOX_MASS`, a body welded to the right hand: the
simulation has no closed chains) by :class:`ArmController` like
joint_trajectory_controller would. Prints the tracking error, contacts, overrun and how well the *executed* motion
kept the hands' grip (the relative-pose error of the simulated arm), and draws the executed motion.

``--through-ros``: the same carry through the nodes (:mod:`maru_planner.ros.carry_demo_run` in a process of its
own: this layer imports no ROS). arm_sim_node (started at the carry's start, the box attached and weighing
:data:`BOX_MASS`) and planning_node run as processes with :func:`through_ros_scene`; one ``plan_motion`` goal with
``execute: true`` plans the carry from its start with the hands' relative pose held (``PathConstraints``' relative
fields: CBiRRT, as in-process) and executes it. The numbers come from what the nodes report and what this process
recorded: the tracking error is the arm's (its result and feedback), contacts are MuJoCo's at every recorded
/joint_states sample (the same model, the box as geometry), the overrun is when /joint_states first stayed within
0.01 rad of the goal, the grip error is the hands' relative pose along the recorded /joint_states.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maru_planner.cli_parser import CliError, OneLineParser
from maru_planner.execution.executor import ArmController, ExecutionResult
from maru_planner.execution.interpolation import checked_points
from maru_planner.execution.tolerances import ResultCode
from maru_planner.physics.arm_model import ServoGains, build_arm_model
from maru_planner.physics.arm_sim import ArmSim, Contact
from maru_planner.planning import MotionPlanner
from maru_planner.planning.dual_arm import DUAL_CARRY, DualArmProblem, relative_pose_error
from maru_planner.planning.types import MotionResult, PlanStatus
from maru_planner.robot import RobotModel
from maru_planner.scene import Scene
from maru_planner.scene.obstacle import Obstacle
from maru_planner.sim.cli import check_writable
from maru_planner.trajectory import Trajectory

BOX = "carried_box"
BOX_SIZE = (0.26, 0.12, 0.12)  # m: along the hands' axis, across, up
BOX_MASS = 1.0  # kg: carried by the right hand's servos in the simulation (a closed chain is not simulated)
GRIP_LINKS = ("r_hand", "l_hand", "r_arm_link5", "l_arm_link5")  # touch the box without colliding
ARRIVAL_TOLERANCE = 0.01  # rad: the arm has arrived when every joint stays this close to the goal
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
    # through the nodes: /joint_states recorded while the carry executed (times from its start, group rows)
    joint_states: tuple[np.ndarray, np.ndarray] | None = None
    reported_tracking: float | None = None  # through the nodes: the arm's own max tracking error (every step)
    goal_status: str | None = None  # through the nodes: how the carry's plan_motion goal ended

    @property
    def executed(self) -> tuple[np.ndarray, np.ndarray]:
        """The executed motion: (times, group rows), /joint_states through the nodes, else the arm's samples."""
        if self.joint_states is not None:
            return self.joint_states
        assert self.execution is not None
        return self.execution.times, self.execution.actual

    def q_full(self, row: np.ndarray) -> np.ndarray:
        """The robot's full configuration with the group at ``row``."""
        q = np.asarray(self.robot.neutral(), dtype=float)
        q[self.robot.group_joint_indices(self.problem.group)] = row
        return q

    def grip_error(self, positions: np.ndarray, start: np.ndarray | None = None) -> tuple[float, float]:
        """Largest hands' relative-pose error (m, rad) along ``positions`` (group rows) from their relative pose at
        ``start`` (default: the problem's start, the nominal grip)."""
        problem = self.problem if start is None else dataclasses.replace(self.problem, start=tuple(start))
        translation, rotation = relative_pose_error(self.robot, problem, positions)
        return float(translation.max()), float(rotation.max())

    def executed_grip_from_its_start(self) -> tuple[float, float]:
        """The executed grip error from the arm's own first sample (which the box's weight has already bent a
        little: the servos' gravity compensation does not know the payload)."""
        rows = self.executed[1]
        return self.grip_error(rows, rows[0])


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


def carry_scene(robot: RobotModel, problem: DualArmProblem, touch_links: tuple[str, ...] = GRIP_LINKS) -> Scene:
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
    scene.attach(BOX, "r_hand", obstacle=obstacle, touch_links=list(touch_links))
    return scene


def through_ros_scene() -> Scene:
    """Both nodes' scene: :func:`carry_scene` (the same as in-process)."""
    return carry_scene(RobotModel.maru1(), carry_problem())


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


class ThroughRosFailed(Exception):
    """The run through the nodes failed (its one line is on stderr already)."""


def run_through_ros(seed: int = 1, real_time_factor: float = 1.0) -> CarryRun:
    """The carry through arm_sim_node and planning_node (:mod:`maru_planner.ros.carry_demo_run`, a process)."""
    with tempfile.TemporaryDirectory(prefix="maru_carry_") as scratch:
        out = Path(scratch) / "run.json"
        command = [sys.executable, "-m", "maru_planner.ros.carry_demo_run", "--json", str(out), "--seed", str(seed)]
        done = subprocess.run([*command, "--real-time-factor", repr(real_time_factor)], stdin=subprocess.DEVNULL)
        if done.returncode != 0 or not out.is_file():
            raise ThroughRosFailed(f"the run through the nodes failed (exit code {done.returncode})")
        record = json.loads(out.read_text())
    return carry_from_record(record)


def carry_from_record(record: dict) -> CarryRun:
    """The :class:`CarryRun` of a recorded run through the nodes (``carry_demo_run``'s JSON)."""
    robot, problem = RobotModel.maru1(), carry_problem()
    scene = through_ros_scene()
    names, plan = list(record["joint_names"]), record["plan"]
    trajectory = Trajectory(
        names, *(np.asarray(plan[k], dtype=float) for k in ("times", "positions", "velocities", "accelerations"))
    )
    motion = MotionResult(PlanStatus.SUCCESS, f"{plan['planner']}, {plan['waypoints']} waypoints", joint_names=names)
    motion.trajectory = trajectory
    feedback = sorted(record["feedback"], key=lambda f: f["stamp"])
    desired = np.array([_ordered(f["names"], f["desired"], names) for f in feedback]).reshape(-1, len(names))
    actual = np.array([_ordered(f["names"], f["actual"], names) for f in feedback]).reshape(-1, len(names))
    rate = float(record["real_time_factor"])  # stamps are wall-clock: simulated time = wall time x this
    feedback_times = np.array([f["stamp"] for f in feedback]) * rate
    start = _start_time(trajectory, feedback_times, desired)
    states = sorted(record["joint_states"], key=lambda s: s["stamp"])
    state_times = np.array([s["stamp"] for s in states]) * rate - start
    state_rows = np.array([_ordered(s["names"], s["positions"], names) for s in states]).reshape(-1, len(names))
    carrying = state_times >= -0.01  # from the execution's start (before it: the arm holding the start)
    state_times, state_rows = state_times[carrying], state_rows[carrying]
    execution = record["execution"]
    run = CarryRun(robot, problem, scene, motion, None, (state_times, state_rows))
    run.execution = ExecutionResult(
        ResultCode(execution["code"]), execution["message"], names, duration=trajectory.duration,
        finished_at=_arrival(state_times, state_rows, trajectory.positions[-1]),
        times=feedback_times - start, desired=desired, actual=actual,
        contacts=_replayed_contacts(run, state_rows),
    )  # fmt: skip
    run.reported_tracking, run.goal_status = float(execution["tracking_error"]), record["goal_status"]
    return run


def _ordered(have: list[str], values: list[float], names: list[str]) -> list[float]:
    index = {name: i for i, name in enumerate(have)}
    return [values[index[name]] for name in names]


def _start_time(trajectory: Trajectory, stamps: np.ndarray, desired: np.ndarray) -> float:
    """When the execution started (stamp clock): each feedback sample's desired point is found on the plan
    (the nearest of a fine sampling), its stamp minus that time; the median over the samples inside the motion."""
    grid = np.linspace(0.0, trajectory.duration, 4000)
    curve = np.column_stack([np.interp(grid, trajectory.times, column) for column in trajectory.positions.T])
    at = np.array([grid[np.argmin(np.abs(curve - row).sum(axis=1))] for row in desired])
    inside = (at > 0.0) & (at < trajectory.duration)
    if not inside.any():
        raise ThroughRosFailed("no execute_trajectory feedback was recorded while the arm moved")
    return float(np.median(stamps[inside] - at[inside]))


def _arrival(times: np.ndarray, rows: np.ndarray, goal: np.ndarray) -> float | None:
    """The first time after which every joint stays within :data:`ARRIVAL_TOLERANCE` of ``goal``."""
    away = np.nonzero(np.abs(rows - goal).max(axis=1) > ARRIVAL_TOLERANCE)[0]
    if len(away) == len(rows):
        return None
    first = 0 if len(away) == 0 else int(away[-1]) + 1
    return float(times[first]) if first < len(times) else None


def _replayed_contacts(run: CarryRun, rows: np.ndarray) -> list[Contact]:
    """MuJoCo's robot-obstacle contacts at every recorded state: the deepest per (link, obstacle)."""
    sim = ArmSim(build_arm_model(run.robot, run.scene, ServoGains(), q0=run.q_full(rows[0])))
    deepest: dict[tuple[str, str], Contact] = {}
    for row in rows:
        sim.reset(run.q_full(row))
        for contact in sim.current_contacts():
            key = (contact.link, contact.obstacle)
            if key not in deepest or contact.depth > deepest[key].depth:
                deepest[key] = contact
    return list(deepest.values())


def summary(run: CarryRun) -> str:
    """One line: the plan, the execution's outcome, tracking error, contacts, overrun and grip errors."""
    if run.execution is None:
        return f"{run.problem.name}: not planned: {run.plan.status.value}: {run.plan.message}"
    result, tr = run.execution, run.plan.trajectory
    assert tr is not None
    planned, executed = run.grip_error(tr.positions), run.grip_error(run.executed[1])
    from_start = run.executed_grip_from_its_start()
    overrun = "never reached" if result.overrun is None else f"{100 * result.overrun:.2f} %"
    if run.joint_states is None:
        waypoints = 0 if run.plan.path is None else len(run.plan.path)
        how, tracking = f"({waypoints} waypoints)", float(result.max_error.max())
        saturated = f", {result.saturated_steps} saturated steps"
    else:
        how = f"by planning_node ({run.plan.message}), executed by arm_sim_node"
        tracking, saturated = float(run.reported_tracking or 0.0), ""
    return (
        f"{run.problem.name}: planned {tr.duration:.2f} s {how}; executed: "
        f"{result.code.name}, max tracking error {tracking:.4f} rad, {len(result.contacts)} contacts, "
        f"overrun {overrun}{saturated}; hands' relative pose held to "
        f"{1e3 * planned[0]:.2f} mm / {planned[1]:.4f} rad planned, {1e3 * executed[0]:.2f} mm / "
        f"{executed[1]:.4f} rad executed ({1e3 * from_start[0]:.2f} mm / {from_start[1]:.4f} rad from the arm's "
        f"own start)"
    )


def main(argv: list[str] | None = None) -> int:
    parser = OneLineParser(prog="carry_demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the picture (PNG)")
    parser.add_argument("--seed", type=int, default=1, help="the planner's seed")
    parser.add_argument(
        "--through-ros", action="store_true", help="arm_sim_node and planning_node as processes (plan_motion, execute)"
    )
    parser.add_argument(
        "--real-time-factor", type=float, default=1.0, help="--through-ros: arm_sim_node's real_time_factor"
    )
    args = parser.parse_args(argv)
    if not 0.01 <= args.real_time_factor <= 100.0:
        parser.error(f"--real-time-factor must be in [0.01, 100], got {args.real_time_factor}")
    if args.out.suffix.lower() != ".png":
        parser.error(f"--out {args.out}: the file name must end in .png")
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        check_writable(args.out, "--out")
    except (OSError, CliError) as exc:
        parser.error(f"--out {args.out}: {exc}" if isinstance(exc, OSError) else str(exc))
    if args.through_ros:
        try:
            run = run_through_ros(args.seed, args.real_time_factor)
        except ThroughRosFailed as exc:
            print(f"carry_demo: {exc}", file=sys.stderr)
            return 1
    else:
        run = run_carry(args.seed)
    print(summary(run))
    if run.execution is None:
        return 1
    from maru_planner.execution.carry_picture import draw_carry  # lazy: matplotlib only for the picture

    print(f"picture {draw_carry(run, args.out)}")
    return 0 if run.execution.success and not run.execution.contacts else 1


if __name__ == "__main__":
    sys.exit(main())
