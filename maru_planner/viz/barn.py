"""Top view of a BARN run: cylinders, the global path, the driven (true) trajectory, contacts (matplotlib, Agg)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from maru_planner.physics.barn_world import CYLINDER_RADIUS, GOAL, START  # noqa: E402
from maru_planner.physics.jackal import JackalSpec  # noqa: E402


def draw_barn_run(
    ax,
    cylinders: np.ndarray,
    trajectory: np.ndarray,
    global_path: np.ndarray,
    contacts: Sequence[tuple[float, float, float]],
    title: str = "",
) -> None:
    """One run on ``ax``: world x across, y (the direction of travel) up."""
    for x, y in cylinders:
        ax.add_patch(Circle((x, y), CYLINDER_RADIUS, color="0.4"))
    ax.add_patch(Circle(GOAL, 1.0, fill=False, ls="--", color="tab:green", lw=1))
    if len(global_path):
        ax.plot(global_path[:, 0], global_path[:, 1], "-", color="tab:orange", lw=1.2, label="last global path")
    if len(trajectory):
        ax.plot(trajectory[:, 0], trajectory[:, 1], "-", color="tab:blue", lw=1.5, label="driven (ground truth)")
        _draw_footprint(ax, trajectory[-1])
    for _, x, y in contacts:
        ax.plot(x, y, "x", color="tab:red", ms=9, mew=2)
    ax.plot(START[0], START[1], "o", color="tab:green", ms=6)
    ax.plot(GOAL[0], GOAL[1], "*", color="k", ms=11)
    ax.set_xlim(-5.0, 0.5)
    ax.set_ylim(-0.3, 14.2)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=8)
    ax.tick_params(labelsize=6)


def _draw_footprint(ax, pose: np.ndarray) -> None:
    corners = JackalSpec().footprint
    c, s = np.cos(pose[2]), np.sin(pose[2])
    world = corners @ np.array([[c, s], [-s, c]]) + pose[:2]
    ax.fill(world[:, 0], world[:, 1], color="tab:blue", alpha=0.4)


def save_barn_runs(path: str | Path, panels: Sequence[dict], columns: int = 5) -> Path:
    """A figure of one or more runs; each panel is the keyword arguments of :func:`draw_barn_run`."""
    n = max(1, len(panels))
    cols = min(columns, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(2.2 * cols, 5.2 * rows), squeeze=False)
    for ax, panel in zip(axes.flat, panels, strict=False):
        draw_barn_run(ax, **panel)
    for ax in list(axes.flat)[len(panels) :]:
        ax.axis("off")
    axes.flat[0].legend(loc="lower left", fontsize=6)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
