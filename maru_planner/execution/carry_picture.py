"""The picture of an executed carry (:mod:`maru_planner.execution.carry_demo`): the simulated arm at a few instants
with the box it carries over the desk, the box's planned and executed paths, the tracking error of every joint and
the hands' relative-pose error of the executed motion."""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from maru_planner.execution.executor import ExecutionResult  # noqa: E402
from maru_planner.planning.dual_arm import DualArmProblem, relative_pose_error  # noqa: E402
from maru_planner.planning.types import MotionResult  # noqa: E402
from maru_planner.robot import RobotModel  # noqa: E402
from maru_planner.robot.attached import robot_with_attached  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402
from maru_planner.viz.plans import clip_faces  # noqa: E402
from maru_planner.viz.robot import draw_configuration  # noqa: E402

BOX = "carried_box"  # carry_demo.BOX (that module imports this one)
SNAPSHOTS = 4  # instants of the executed motion drawn
VIEWS = ((30.0, 20.0), (88.0, 180.0))  # (elevation, azimuth): from the front of the desk, from above
LIMITS = np.array([[-0.15, -0.55, -0.25], [0.75, 0.55, 0.75]])  # m: the view (base_link frame)


class CarryRun(Protocol):
    """What is drawn: ``carry_demo.CarryRun`` (that module imports this one)."""

    robot: RobotModel
    problem: DualArmProblem
    scene: Scene
    plan: MotionResult
    execution: ExecutionResult | None
    joint_states: tuple[np.ndarray, np.ndarray] | None

    @property
    def executed(self) -> tuple[np.ndarray, np.ndarray]: ...

    def q_full(self, row: np.ndarray) -> np.ndarray: ...


def draw_carry(run: CarryRun, out: Path) -> Path:
    """Draw ``run`` (executed) to ``out`` (PNG); returns ``out``."""
    result, trajectory = run.execution, run.plan.trajectory
    assert result is not None and trajectory is not None
    carrying = robot_with_attached(run.robot, run.scene)
    fig = plt.figure(figsize=(16, 6.2))
    grid = fig.add_gridspec(2, 3, width_ratios=(1.15, 1.15, 1.0))
    for column, (elevation, azimuth) in enumerate(VIEWS):
        ax = fig.add_subplot(grid[:, column], projection="3d")
        _draw_motion(ax, run, carrying)
        ax.view_init(elev=elevation, azim=azimuth)
    error_ax, grip_ax = fig.add_subplot(grid[0, 2]), fig.add_subplot(grid[1, 2])
    for j, name in enumerate(result.joint_names):
        error_ax.plot(result.times, 1e3 * result.error[:, j], lw=0.8, label=name)
    error_ax.set_ylabel("planned - executed (mrad)")
    source = "" if run.joint_states is None else ", arm_sim_node's feedback"
    error_ax.set_title(f"tracking error per joint{source} (max {1e3 * result.max_error.max():.2f} mrad)", fontsize=9)
    error_ax.legend(fontsize=5, ncol=4, loc="lower left")
    executed_times, executed = run.executed
    for positions, times, style, label in (
        (trajectory.positions, trajectory.times, "C0--", "planned"),
        (executed, executed_times, "C3-", "executed"),
    ):
        translation, rotation = relative_pose_error(run.robot, run.problem, positions)
        grip_ax.plot(times, 1e3 * translation, style, lw=1.2, label=f"{label}: position (mm)")
        grip_ax.plot(times, 1e2 * rotation, style, lw=0.6, alpha=0.6, label=f"{label}: rotation (x0.01 rad)")
    grip_ax.set_title("hands' relative pose, error from the start's (the grip on the box)", fontsize=9)
    grip_ax.set_xlabel("time (s)")
    grip_ax.legend(fontsize=6)
    overrun = "-" if result.overrun is None else f"{100 * result.overrun:.2f} %"
    where = "MuJoCo" if run.joint_states is None else "arm_sim_node (MuJoCo), planned by planning_node"
    fig.suptitle(
        f"Maru-1 carries a box across the desk, executed in {where}: {result.code.name}, {len(result.contacts)} "
        f"contacts, planned {trajectory.duration:.2f} s, overrun {overrun}",
        fontsize=10,
    )
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def _draw_motion(ax, run: CarryRun, carrying) -> None:
    result, trajectory = run.execution, run.plan.trajectory
    assert result is not None and trajectory is not None
    for obstacle in run.scene.obstacles.values():
        faces = clip_faces(obstacle.faces(), LIMITS)
        if faces:
            ax.add_collection3d(Poly3DCollection(faces, alpha=0.15, facecolor="tan", edgecolor="k", linewidth=0.3))
    times, executed = run.executed
    instants = np.linspace(0, len(times) - 1, SNAPSHOTS).round().astype(int)
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.85, SNAPSHOTS))
    for k, colour in zip(instants, colours, strict=True):
        q = run.q_full(executed[k])
        draw_configuration(ax, carrying, None, q, colour, highlight=(BOX,), alpha=0.3)
        ax.text(*_box_centre(carrying, q) + [0, 0, 0.1], f"{times[k]:.2f} s", fontsize=7)
    for positions, style, label in (
        (trajectory.positions, "k--", "box centre planned"),
        (executed, "r-", "executed"),
    ):
        centres = np.array([_box_centre(carrying, run.q_full(row)) for row in positions])
        ax.plot(centres[:, 0], centres[:, 1], centres[:, 2], style, lw=2.0, label=label)
    for setter, low, high in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), *LIMITS, strict=True):
        setter(low, high)
    ax.set_box_aspect(LIMITS[1] - LIMITS[0])
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(fontsize=7, loc="upper left")


def _box_centre(carrying, q: np.ndarray) -> np.ndarray:
    return np.asarray(carrying.frame_pose(q, BOX)[:3, 3], dtype=float)
