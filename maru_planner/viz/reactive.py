"""Pictures of the reactive layer: worlds, trajectories, elastic strips around obstacles (matplotlib, Agg)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402
from PIL import Image  # noqa: E402

STRIP_COLOURS = {
    "modified": "tab:blue",
    "plain": "tab:red",
    "baseline": "tab:gray",
    "modified_literal": "tab:purple",
    "modified_straight": "tab:cyan",
}


def draw_world(ax, world, t: float = 0.0, mover_offset: float = 0.0, show_movers: bool = True) -> None:
    """Obstacles (grey), movers at time ``t`` (orange), start (green) and goal (star)."""
    if world.occupancy is not None:
        occ = world.occupancy
        h, w = occ.occupied.shape
        ax.imshow(
            occ.occupied,
            origin="lower",
            cmap="Greys",
            alpha=0.6,
            extent=(
                occ.origin[0],
                occ.origin[0] + w * occ.resolution,
                occ.origin[1],
                occ.origin[1] + h * occ.resolution,
            ),
        )
    for x, y, r in world.circles:
        ax.add_patch(Circle((x, y), r, color="0.45"))
    for poly in world.polygons:
        ax.add_patch(Polygon(poly, closed=True, color="0.45"))
    if show_movers:
        for m in world.movers:
            pos = m.position(t, mover_offset)
            ax.add_patch(Circle(pos, m.radius, color="tab:orange", alpha=0.7))
            ax.plot(m.waypoints[:, 0], m.waypoints[:, 1], ":", color="tab:orange", lw=1)
    s, g = world.robot.start, world.robot.goal
    ax.plot(s[0], s[1], "o", color="tab:green", ms=7)
    ax.plot(g[0], g[1], "*", color="k", ms=12)
    if world.bounds is not None:
        ax.set_xlim(world.bounds[0], world.bounds[2])
        ax.set_ylim(world.bounds[1], world.bounds[3])
    ax.set_aspect("equal")


def draw_run(
    ax,
    result,
    colour: str = "tab:blue",
    label: str | None = None,
    strips: bool = True,
    robot_radius: float | None = None,
) -> None:
    """A run's trajectory, the strip snapshots it recorded, and where it ended."""
    traj = np.asarray(result.trajectory)
    ax.plot(traj[:, 0], traj[:, 1], "-", color=colour, lw=1.5, label=label)
    if strips:
        for _t, _pose, strip, _pts in result.strips:
            ax.plot(strip[:, 0], strip[:, 1], ".-", color=colour, lw=0.6, ms=2, alpha=0.45)
    end = traj[-1]
    marker = {"goal": "o", "collision": "X", "timeout": "s"}.get(result.outcome, "o")
    ax.plot(end[0], end[1], marker, color=colour, ms=9, mec="k")
    if robot_radius:
        ax.add_patch(Circle(end[:2], robot_radius, fill=False, color=colour, lw=1))


def draw_strip_snapshot(ax, snapshot, colour: str = "tab:blue", robot_radius: float = 0.3) -> None:
    """One strip with the obstacle points it saw and the robot's body."""
    _t, pose, strip, points = snapshot
    if len(points):
        ax.plot(points[:, 0], points[:, 1], ".", color="tab:red", ms=2)
    ax.plot(strip[:, 0], strip[:, 1], "o-", color=colour, lw=1.2, ms=3)
    ax.add_patch(Circle(pose[:2], robot_radius, fill=False, color=colour))
    ax.arrow(pose[0], pose[1], 0.4 * np.cos(pose[2]), 0.4 * np.sin(pose[2]), width=0.02, color=colour)


def save_run_picture(path, world, results: dict, title: str = "") -> None:
    """One panel: the world and each labelled run (e.g. {"modified": r1, "plain": r2})."""
    fig, ax = plt.subplots(figsize=(8, 5))
    draw_world(ax, world, show_movers=False)
    for label, result in results.items():
        draw_run(
            ax,
            result,
            STRIP_COLOURS.get(label, "tab:purple"),
            f"{label}: {result.outcome}",
            robot_radius=world.robot.bounding_radius,
        )
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title or world.name)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def save_run_gif(path, world, result, fps: int = 10, robot_radius: float = 0.3, mover_offset: float = 0.0) -> None:
    """Animated GIF of a run from its strip snapshots (needs strip_every > 0 in the run)."""
    frames = []
    for snap in result.strips:
        fig, ax = plt.subplots(figsize=(6, 4))
        draw_world(ax, world, t=snap[0], mover_offset=mover_offset)
        traj = np.asarray(result.trajectory)
        ax.plot(traj[:, 0], traj[:, 1], "-", color="0.7", lw=1)
        draw_strip_snapshot(ax, snap, robot_radius=robot_radius)
        ax.set_title(f"{world.name}  t = {snap[0]:.1f} s")
        fig.tight_layout()
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        frames.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3]))
        plt.close(fig)
    if frames:
        frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 / fps), loop=0)
