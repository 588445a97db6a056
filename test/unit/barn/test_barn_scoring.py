"""The BARN metric exactly as the challenge computes it, and the optimal time of any grid."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.barn.scoring import RunScore, barn_metric, grid_optimal_time, summarise
from maru_planner.errors import NoPath
from maru_planner.physics.barn_world import barn_dir, optimal_time, world_grid


@pytest.mark.parametrize(
    "success, time_s, optimal, expected",
    [
        (True, 5.0, 6.0, 0.5),  # faster than 2 OT: clipped to 2 OT
        (True, 24.0, 6.0, 0.25),
        (True, 90.0, 6.0, 0.125),  # slower than 8 OT: clipped to 8 OT
        (False, 10.0, 6.0, 0.0),
        (True, None, 6.0, 0.0),
    ],
)
def test_metric(success, time_s, optimal, expected):
    assert barn_metric(success, time_s, optimal) == pytest.approx(expected)


@pytest.mark.skipif(not (barn_dir() / "worlds.csv").is_file(), reason="BARN data not present")
def test_grid_optimal_time_is_near_the_challenges():
    for world in (0, 100, 250):
        assert abs(grid_optimal_time(world_grid(world)) / optimal_time(world) - 1.0) < 0.2


def test_grid_without_a_free_path_is_refused():
    grid = np.zeros((30, 30), np.uint8)
    grid[:, 12] = 1  # a wall across the field
    with pytest.raises(NoPath, match="no free path"):
        grid_optimal_time(grid)
    assert grid_optimal_time(np.zeros((30, 30), np.uint8)) == pytest.approx(67 * 0.15 / 2)


def test_summary_averages_worlds_then_runs():
    def run(world: str, metric: float, success: bool) -> RunScore:
        return RunScore(world, 0, success, not success, False, 10.0, 5.0, metric, 0.1, 20.0, 2.0)

    summary = summarise([run("a", 0.5, True), run("a", 0.0, False), run("b", 0.25, True)])
    assert summary["mean_metric"] == pytest.approx((0.25 + 0.25) / 2)
    assert summary["success_rate"] == pytest.approx(2 / 3, abs=1e-3)
    assert summary["collision_rate"] == pytest.approx(1 / 3, abs=1e-3)
    assert summary["realtime_factor"] == pytest.approx(10.0) and summary["worlds"] == 2
