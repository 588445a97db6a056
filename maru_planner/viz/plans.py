"""Pictures of planned arm motions: hand traces over the scene's obstacles (any shape), from two views."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

VIEWS = (("front-left", 22, -140), ("top", 80, -90))
TRACE_COLORS = ("tab:red", "tab:blue", "tab:green", "tab:purple")


def joint_positions(robot, q: np.ndarray) -> np.ndarray:
    """World positions of every joint origin (a stick figure of the robot)."""
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, np.asarray(q, float))
    return np.array([data.oMi[j].translation for j in range(1, robot.model.njoints)])


def hand_traces(robot, positions: np.ndarray, base_q: np.ndarray, indices, frames) -> dict[str, np.ndarray]:
    """Frame → (n, 3) positions along the group configurations ``positions``."""
    traces = {}
    for frame in frames:
        pts = []
        for row in positions:
            q = np.array(base_q, float)
            q[indices] = row
            pts.append(robot.frame_pose(q, frame)[:3, 3])
        traces[frame] = np.array(pts)
    return traces


def _draw_stick(ax, robot, q, color, label):
    pts = joint_positions(robot, q)
    parents = robot.model.parents
    for j in range(2, robot.model.njoints):
        p = parents[j]
        if p >= 1:
            seg = np.array([pts[p - 1], pts[j - 1]])
            ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color=color, lw=2, alpha=0.7)
    ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], color=color, s=8, label=label)


def plot_plan(robot, scene, result, out_path, title: str = "", base_q=None) -> Path:
    """Two 3-D views of the hand traces of ``result`` (a successful MotionResult) over the obstacles."""
    out_path = Path(out_path)
    names = list(result.joint_names)
    indices = [robot.joint_names.index(n) for n in names]
    base = np.asarray(robot.neutral() if base_q is None else base_q, dtype=float)
    positions = result.trajectory.positions if result.trajectory is not None else result.path
    frames = [f for f in getattr(robot, "end_effectors", {}).values() if _frame_moves(robot, f, base, indices)]
    traces = hand_traces(robot, positions, base, indices, frames)
    waypoint_traces = hand_traces(robot, result.path, base, indices, frames)
    q_start, q_goal = base.copy(), base.copy()
    q_start[indices], q_goal[indices] = result.path[0], result.path[-1]

    fig = plt.figure(figsize=(12, 5.5))
    for k, (view, elev, azim) in enumerate(VIEWS):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        limits = _equal_axes(
            ax, np.vstack([*traces.values(), joint_positions(robot, q_start), joint_positions(robot, q_goal)])
        )
        for obstacle in scene.obstacles.values() if scene is not None else ():
            faces = clip_faces(obstacle.faces(), limits)
            if faces:
                ax.add_collection3d(Poly3DCollection(faces, alpha=0.18, facecolor="tan", edgecolor="k"))
        _draw_stick(ax, robot, q_start, "0.55", "start")
        _draw_stick(ax, robot, q_goal, "0.15", "goal")
        for c, (frame, pts) in enumerate(traces.items()):
            color = TRACE_COLORS[c % len(TRACE_COLORS)]
            ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], color=color, lw=2, label=f"{frame} trace")
            wp = waypoint_traces[frame]
            ax.scatter(wp[:, 0], wp[:, 1], wp[:, 2], color=color, s=18, marker="o")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
        ax.view_init(elev=elev, azim=azim)
        ax.set_title(view)
        if k == 0:
            ax.legend(loc="upper left", fontsize=8)
    s = result.stats
    fig.suptitle(
        f"{title}  —  {len(result.path)} waypoints, {s.path_length:.2f} rad, "
        f"solve {s.solve_time * 1e3:.0f} ms, trajectory {result.trajectory.duration:.2f} s"
    )
    fig.tight_layout()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_path, dpi=110)
    plt.close(fig)
    return out_path


def _frame_moves(robot, frame: str, base, indices) -> bool:
    """True if any group joint moves ``frame`` (finite-difference on the Jacobian columns)."""
    try:
        jac = robot.frame_jacobian(base, frame)
    except Exception:
        return False
    return bool(np.abs(np.asarray(jac)[:, indices]).max() > 1e-9)


def _equal_axes(ax, pts: np.ndarray) -> np.ndarray:
    """Cube-shaped limits around ``pts``; returns them as a (2, 3) array (low row, high row)."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2 * 1.05, 0.3)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    return np.array([centre - half, centre + half])


def clip_faces(faces: list[np.ndarray], limits: np.ndarray) -> list[np.ndarray]:
    """Polygons with their corners clamped into the plot limits (3-D axes do not clip); [] if all outside.

    Exact for axis-aligned boxes (a table larger than the view is cut to it); other shapes only lose
    what sticks out of the view.
    """
    corners = np.concatenate(faces)
    if np.any(corners.max(axis=0) < limits[0]) or np.any(corners.min(axis=0) > limits[1]):
        return []
    return [np.clip(f, limits[0], limits[1]) for f in faces]
