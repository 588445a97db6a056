"""Line-of-sight shortcuts on grid cells (the tunnel planner's last step, paper 003): a segment between two cell
centres is free when it crosses only free cells, and a cell chain keeps only its turning points."""

from __future__ import annotations

import numpy as np

from maru_planner.base.budget import Deadline, unlimited


def segment_is_free(occupied: np.ndarray, a, b) -> bool:
    """True when the segment between the centres of cells a and b crosses only free cells.

    Conservative: samples every quarter cell and tests the 2 × 2 cells around
    each sample's ±0.25 box, so a segment grazing a corner counts as touching it.
    """
    (r0, c0), (r1, c1) = a, b
    n = int(np.ceil(4.0 * max(abs(r1 - r0), abs(c1 - c0)))) + 1
    t = np.linspace(0.0, 1.0, n)
    rows = r0 + 0.5 + t * (r1 - r0)
    cols = c0 + 0.5 + t * (c1 - c0)
    h, w = occupied.shape
    for dr in (-0.25, 0.25):
        for dc in (-0.25, 0.25):
            ri = np.clip(np.floor(rows + dr).astype(int), 0, h - 1)
            ci = np.clip(np.floor(cols + dc).astype(int), 0, w - 1)
            if occupied[ri, ci].any():
                return False
    return True


def segment_max_cost(cost: np.ndarray, a, b) -> int:
    """The highest cost among the cells :func:`segment_is_free` reads for the segment a-b."""
    (r0, c0), (r1, c1) = a, b
    n = int(np.ceil(4.0 * max(abs(r1 - r0), abs(c1 - c0)))) + 1
    t = np.linspace(0.0, 1.0, n)
    rows, cols = r0 + 0.5 + t * (r1 - r0), c0 + 0.5 + t * (c1 - c0)
    h, w = cost.shape
    ri = np.clip(np.floor(rows[:, None] + np.array([-0.25, 0.25])).astype(int), 0, h - 1)
    ci = np.clip(np.floor(cols[:, None] + np.array([-0.25, 0.25])).astype(int), 0, w - 1)
    return int(cost[ri[:, :, None], ci[:, None, :]].max())


def shortcut_cells(
    occupied: np.ndarray, cells: list, deadline: Deadline | None = None, cost: np.ndarray | None = None
) -> list:
    """Keep only the turning points: from each anchor, the farthest cell still in line of sight.

    With ``cost`` (a cost layer), a shortcut is taken only where it crosses no cell costlier than the
    chain it replaces: it never cuts closer to an obstacle than the chain did.
    When ``deadline`` passes, the rest of the chain is kept as it is (still a valid path).
    """
    if len(cells) <= 2:
        return list(cells)
    deadline = deadline or unlimited()
    out = [cells[0]]
    anchor = 0
    chain_max = -1
    j = 1
    while j < len(cells):
        if deadline.expired():
            return out + list(cells[anchor + 1 :])
        if cost is not None:
            chain_max = max(chain_max, segment_max_cost(cost, cells[j - 1], cells[j]))
        if segment_is_free(occupied, cells[anchor], cells[j]) and (
            cost is None or j == anchor + 1 or segment_max_cost(cost, cells[anchor], cells[j]) <= chain_max
        ):
            j += 1
            continue
        anchor = j - 1
        chain_max = -1 if cost is None else segment_max_cost(cost, cells[anchor], cells[j])
        out.append(cells[anchor])
    out.append(cells[-1])
    return out
