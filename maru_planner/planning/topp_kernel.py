"""Old home of toppra's numba kernel: :mod:`maru_planner.trajectory.toppra_kernel` now (re-exported here)."""

from maru_planner.trajectory.toppra_kernel import (
    TINY,
    highest_x,
    largest_u,
    peak_ratios_nb,
    profile_states_nb,
    rest_to_rest_nb,
    stage_rows_nb,
)

__all__ = [
    "TINY",
    "highest_x",
    "largest_u",
    "peak_ratios_nb",
    "profile_states_nb",
    "rest_to_rest_nb",
    "stage_rows_nb",
]
