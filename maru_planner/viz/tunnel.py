"""Pictures of the tunnel planner's stages (paper 003, Fig. 5 c–f): T, lumped cells, B, PFP path, final path."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import ArrayLike  # noqa: E402


def big_cells_mask(cells: ArrayLike, size: int, shape) -> np.ndarray:
    """Small-cell mask covered by the big cells ``cells`` (k, 2) of ``size``."""
    mask = np.zeros(shape, dtype=bool)
    for r, c in np.asarray(cells, dtype=int).reshape(-1, 2):
        mask[r * size : (r + 1) * size, c * size : (c + 1) * size] = True
    return mask


def _base(ax, occupied, grown, title):
    img = np.ones(occupied.shape + (3,))
    img[grown] = (0.75, 0.75, 0.75)
    img[occupied] = (0.1, 0.1, 0.1)
    ax.imshow(img, origin="lower", interpolation="nearest")
    ax.set_title(title, fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])


def _overlay(ax, mask, color, alpha=0.45):
    rgba = np.zeros(mask.shape + (4,))
    rgba[mask] = (*color, alpha)
    ax.imshow(rgba, origin="lower", interpolation="nearest")


def draw_stages(
    occupied: np.ndarray,
    grown: np.ndarray,
    attempts: list,
    raw_cells: np.ndarray,
    waypoints: np.ndarray,
    start_cell,
    goal_cell,
    title: str = "",
):
    """A 1 × 4 figure: tunnel T with lumped cells, thin tunnel B, PFP cell path, final path."""
    fig, axes = plt.subplots(1, 4, figsize=(16, 4.4))
    last = attempts[-1] if attempts else None
    size = last.big_cell_size if last else 1
    shape = occupied.shape
    _base(axes[0], occupied, grown, f"TFP: tunnel T ({len(last.tunnel) if last else 0} big cells of {size}×{size})")
    if last is not None:
        _overlay(axes[0], big_cells_mask(last.tunnel, size, shape), (0.2, 0.4, 1.0))
        _overlay(axes[0], big_cells_mask(last.lumped, size, shape), (1.0, 0.3, 0.0), 0.7)
    _base(axes[1], occupied, grown, f"LCRP: thin tunnel B ({len(last.thin_tunnel) if last else 0} big cells)")
    if last is not None:
        _overlay(axes[1], big_cells_mask(last.thin_tunnel, size, shape), (0.1, 0.7, 0.2))
        for vo in last.virtual_obstacles:
            for big in vo:
                _overlay(axes[1], big_cells_mask([big], size, shape), (0.9, 0.0, 0.9), 0.8)
    _base(axes[2], occupied, grown, f"PFP: {len(raw_cells)} small cells")
    if len(raw_cells):
        axes[2].plot(raw_cells[:, 1], raw_cells[:, 0], "-", color=(0.8, 0.1, 0.1), lw=1)
    _base(axes[3], occupied, grown, f"final path: {max(len(waypoints) - 2, 0)} turning points")
    if len(waypoints):
        axes[3].plot(waypoints[:, 1], waypoints[:, 0], "o-", color=(0.8, 0.1, 0.1), lw=1.5, ms=3)
    for ax in axes:
        ax.plot(start_cell[1], start_cell[0], "o", color="blue", ms=7)
        ax.plot(goal_cell[1], goal_cell[0], "o", color="limegreen", ms=7)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def save_stages_png(path, *args, **kwargs) -> None:
    fig = draw_stages(*args, **kwargs)
    fig.savefig(path, dpi=110)
    plt.close(fig)
