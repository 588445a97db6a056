"""Pictures for paper 004: the 3-D scene, its 2-D map (line / virtual obstacles) and the biped paths."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from maru_planner.base.biped.mapping import LINE, LINE_AND_VIRTUAL, OVERHEAD, STEPPABLE, VIRTUAL, classify  # noqa: E402

CLASS_COLOURS = {
    STEPPABLE: "#9ccc65",
    LINE: "#ffb74d",
    VIRTUAL: "#64b5f6",
    LINE_AND_VIRTUAL: "#78909c",
    OVERHEAD: "#e0e0e0",
}


def draw_scene_3d(ax, world) -> None:
    """Boxes coloured by what they become for the robot."""
    for box in world.obstacles:
        corners = box.corners()
        z0, z1 = box.z
        bottom = [(x, y, z0) for x, y in corners]
        top = [(x, y, z1) for x, y in corners]
        faces = [bottom, top] + [[bottom[i], bottom[(i + 1) % 4], top[(i + 1) % 4], top[i]] for i in range(4)]
        colour = CLASS_COLOURS[classify(box, world.robot)]
        ax.add_collection3d(Poly3DCollection(faces, facecolor=colour, edgecolor="k", linewidths=0.3, alpha=0.6))
    xmin, ymin, xmax, ymax = world.bounds
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_zlim(0, max([b.z[1] for b in world.obstacles] + [world.robot.height]))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")


def draw_map_2d(ax, m) -> None:
    """Virtual obstacles (body, grown) in blue, line obstacles (gait) in orange."""
    img = np.ones(m.shape + (3,))
    img[m.virtual] = (0.55, 0.75, 0.95)
    img[m.line] = (0.95, 0.6, 0.2)
    extent = (
        m.origin[0],
        m.origin[0] + m.shape[1] * m.resolution,
        m.origin[1],
        m.origin[1] + m.shape[0] * m.resolution,
    )
    ax.imshow(img, origin="lower", extent=extent, interpolation="nearest")
    ax.set_aspect("equal")


def draw_rectangle(ax, pose, length, width, **style) -> None:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    local = np.array(
        [
            [-length / 2, -width / 2],
            [length / 2, -width / 2],
            [length / 2, width / 2],
            [-length / 2, width / 2],
            [-length / 2, -width / 2],
        ]
    )
    pts = local @ np.array([[c, s], [-s, c]]) + pose[:2]
    ax.plot(pts[:, 0], pts[:, 1], **style)


def draw_path(ax, path, robot, colour, label, every: int = 1) -> None:
    if len(path) == 0:
        return
    ax.plot(path[:, 0], path[:, 1], "-", color=colour, lw=1.5, label=label)
    for pose in path[::every]:
        draw_rectangle(ax, pose, robot.gait_length, robot.gait_width, color=colour, lw=0.5, alpha=0.6)


def draw_scene_figure(world, m, plans: dict, title: str = ""):
    """3-D scene | one 2-D map with the path per entry of ``plans`` (id -> BasePlanResult)."""
    cols = 1 + len(plans)
    fig = plt.figure(figsize=(5.7 * cols, 5))
    ax3 = fig.add_subplot(1, cols, 1, projection="3d")
    draw_scene_3d(ax3, world)
    ax3.set_title("3-D scene (colour = mapping class)", fontsize=9)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in CLASS_COLOURS.values()]
    ax3.legend(handles, list(CLASS_COLOURS), fontsize=7, loc="upper left")
    colours = {"biped_track": "tab:green", "biped_wall": "tab:red"}
    for i, (name, plan) in enumerate(plans.items()):
        ax = fig.add_subplot(1, cols, 2 + i)
        draw_map_2d(ax, m)
        track = plan.layers.get("track_edges")
        if track is not None and len(track):
            for seg in track:
                ax.plot(seg[:, 0], seg[:, 1], "-", color="0.6", lw=0.4)
        every = 1 if name == "biped_track" else 6
        draw_path(ax, plan.path, world.robot, colours.get(name, "k"), name, every)
        if world.start is not None:
            ax.plot(*world.start[:2], "bo")
            ax.plot(*world.goal[:2], "o", color="limegreen")
        ax.set_title(f"{name}: {plan.status.value} ({plan.stats.planning_time:.3f} s)\n{plan.message[:70]}", fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def save_scene_png(path, *args, **kwargs) -> None:
    fig = draw_scene_figure(*args, **kwargs)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def save_result_png(path, result, planner_id: str) -> None:
    """Picture of one biped result planned on a 3-D world (``result.layers`` holds the world and its map)."""
    world, m = result.layers.get("world"), result.layers.get("map")
    if world is None or m is None:
        raise ValueError("the result carries no 3-D world (plan with --world)")
    save_scene_png(path, world, m, {planner_id: result}, f"{world.name}: {planner_id} {result.status.value}")
