"""Ruckig's blends stay within the joints' range of the path (so within the joint limits the path keeps)."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.trajectory import Limits, parameterize

# MotionBenchMaker bookshelf_small/0001 (Panda, RRTConnect seed 0): panda_joint3 goes down to -2.8958 at the middle
# waypoint, 1.5 mrad above its lower limit -2.8973, and turns back by 0.011 rad. Ruckig's time-synchronised blend
# there, shrunk once to 0.2 rad by the certifier, went 0.054 rad below the limit.
BOOKSHELF_PATH = np.array(
    [
        [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785],
        [1.561436, 0.454137, -2.895788, -2.760767, 2.34846, 2.168038, -1.371893],
        [1.489049, -0.146671, -2.884975, -2.174557, 2.709923, 2.35321, 1.061964],
    ]
)
PANDA_LIMITS = Limits.scaled([2.175] * 4 + [2.61] * 3, [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
PANDA_JOINT3_LOWER = -2.8973
NAMES = [f"panda_joint{i}" for i in range(1, 8)]


def always_free(_states: np.ndarray, _deviation: np.ndarray) -> bool:
    return True


def timed(path: np.ndarray, method: str, deviation: float = 0.8):
    return parameterize(path, NAMES, PANDA_LIMITS, method, curve_free=always_free, max_deviation=deviation, dt=0.002)


@pytest.mark.parametrize(("method", "deviation"), [("ruckig", 0.2), ("ruckig", 0.8), ("toppra", 0.2)])
def test_a_blend_near_a_joint_limit_does_not_cross_it(method, deviation):
    trajectory, report = timed(BOOKSHELF_PATH, method, deviation)
    assert trajectory.positions[:, 2].min() >= PANDA_JOINT3_LOWER
    box = BOOKSHELF_PATH.min(axis=0) - 1e-9, BOOKSHELF_PATH.max(axis=0) + 1e-9
    assert np.all((trajectory.positions >= box[0]) & (trajectory.positions <= box[1]))
    assert report.method == method  # still blended by the method asked for, not a fallback to trapezoids
    np.testing.assert_allclose(trajectory.positions[-1], BOOKSHELF_PATH[-1], atol=1e-9)


def test_a_joint_turning_at_the_edge_of_its_range_stays_within_it():
    rng = np.random.default_rng(7)
    for _ in range(12):  # before the fix 2 of these 12 left the range by 0.031 rad
        path = rng.uniform(-1.0, 1.0, (3, 7))
        joint = rng.integers(7)
        path[1:, joint] = -1.0, rng.uniform(-1.0, -0.95)  # goes to the edge and turns back a little
        trajectory, report = timed(path, "ruckig", 0.2)
        assert report.method == "ruckig"
        assert np.all(trajectory.positions >= path.min(axis=0) - 1e-9)
        assert np.all(trajectory.positions <= path.max(axis=0) + 1e-9)
