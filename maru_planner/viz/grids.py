"""Pictures of occupancy grids, grown maps and base paths (matplotlib, Agg)."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Polygon, Rectangle  # noqa: E402


def _axes(ax=None, figsize=(7, 5)):
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
    return ax.figure, ax


def grid_extent(grid):
    """imshow extent in metres (origin yaw ignored for drawing)."""
    ox, oy, _ = grid.origin
    return (ox, ox + grid.width * grid.resolution, oy, oy + grid.height * grid.resolution)


def draw_grid(ax, grid, layers: dict | None = None):
    """Obstacles black, unknown grey, grown layers (eca, baa, grown) tinted."""
    rgb = np.ones(grid.shape + (3,))
    tints = {"baa": (1.0, 0.85, 0.6), "grown": (1.0, 0.85, 0.6), "eca": (1.0, 0.6, 0.6)}
    for name in ("baa", "grown", "eca"):
        layer = (layers or {}).get(name)
        if layer is not None and np.shape(layer) == grid.shape:
            rgb[np.asarray(layer, dtype=bool)] = tints[name]
    rgb[grid.unknown] = (0.7, 0.7, 0.7)
    rgb[grid.occupied & ~grid.unknown] = (0.0, 0.0, 0.0)
    ax.imshow(rgb, origin="lower", extent=grid_extent(grid), interpolation="nearest")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def draw_footprint(ax, footprint, pose, **kw):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    pts = np.asarray(footprint) @ np.array([[c, s], [-s, c]]) + np.asarray(pose[:2])
    ax.add_patch(Polygon(pts, closed=True, fill=False, **kw))


def draw_path(ax, grid, path, footprint=None, every: int | None = None, color="tab:blue"):
    path = np.asarray(path).reshape(-1, 3)
    if len(path) == 0:
        return
    ax.plot(path[:, 0], path[:, 1], "-", color=color, lw=1.5)
    if footprint is not None:
        every = every or max(1, len(path) // 12)
        for pose in path[::every]:
            draw_footprint(ax, footprint, pose, edgecolor=color, lw=0.6, alpha=0.7)
        draw_footprint(ax, footprint, path[-1], edgecolor=color, lw=0.8)


def draw_windows(ax, grid, windows):
    for r0, c0, r1, c1 in np.asarray(windows).reshape(-1, 4):
        x0, y0 = grid.origin[0] + c0 * grid.resolution, grid.origin[1] + r0 * grid.resolution
        ax.add_patch(
            Rectangle(
                (x0, y0),
                (c1 - c0) * grid.resolution,
                (r1 - r0) * grid.resolution,
                fill=False,
                edgecolor="tab:green",
                lw=1.0,
                ls="--",
            )
        )


def plot_plan(grid, result, start=None, goal=None, footprint=None, title: str = "", ax=None):
    """One picture: grid, grown maps, path, footprints, windows; returns the figure."""
    fig, ax = _axes(ax)
    draw_grid(ax, grid, result.layers if result is not None else None)
    if result is not None:
        draw_path(ax, grid, result.path, footprint)
        if "windows" in result.layers:
            draw_windows(ax, grid, result.layers["windows"])
    for pose, color in ((start, "tab:green"), (goal, "tab:red")):
        if pose is not None:
            ax.plot(pose[0], pose[1], "o", color=color, ms=5)
            if footprint is not None and len(pose) > 2:
                draw_footprint(ax, footprint, pose, edgecolor=color, lw=1.2)
    if title:
        ax.set_title(title, fontsize=9)
    return fig


def save_plan_png(path, grid, result, start=None, goal=None, footprint=None, title: str = ""):
    fig = plot_plan(grid, result, start, goal, footprint, title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
