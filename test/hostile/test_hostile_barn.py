"""Bad input to maru-barn and the simulated base: bad grid files, no free path, NaN commands, a silent controller."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.barn.cli import main
from maru_planner.barn.stack import StackConfig, run_barn
from maru_planner.physics.base_sim import BaseSim


def _blocked() -> np.ndarray:
    grid = np.zeros((30, 30), np.uint8)
    grid[:, 15] = 1
    return grid


@pytest.mark.parametrize(
    "content, words",
    [
        (np.zeros((30, 31), np.uint8), "shape"),
        (np.zeros((30, 30), np.float32), "dtype"),
        (np.full((30, 30), 7, np.uint8), "only 0 and 1"),
        (np.zeros((30, 30, 1), np.uint8), "shape"),
        (_blocked(), "no free path"),
        (b"\x93NUMPY garbage", "cannot read grid file"),
        (b"", "cannot read grid file"),
    ],
)
def test_bad_grid_file_is_one_line_exit_2(tmp_path, capsys, content, words):
    path = tmp_path / "grid.npy"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        np.save(path, content)
    assert main(["--grid", str(path), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err and "Traceback" not in err


@pytest.mark.parametrize(
    "argv",
    [["--world", "300"], ["--world", "-1"], ["--world", "0", "--trials", "0"], ["--world", "0", "--seed", "-2"]],
)
def test_bad_options_exit_2(capsys, argv):
    assert main([*argv, "--quiet"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_unwritable_outputs_exit_2_before_running(tmp_path, capsys):
    assert main(["--world", "0", "--json", str(tmp_path / "missing" / "out.json"), "--quiet"]) == 2
    assert main(["--world", "0", "--png", str(tmp_path / "out.jpg"), "--quiet"]) == 2
    assert "must end in .png" in capsys.readouterr().err


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_command_stops_the_base(bad):
    sim = BaseSim(np.zeros((30, 30), np.uint8))
    for _ in range(20):
        sim.command(1.0, 0.0)
        sim.advance(0.05)
    for _ in range(20):
        sim.command(bad, 0.5)
        sim.advance(0.05)
    assert abs(sim.true_twist()[0]) < 0.05 and abs(sim.true_twist()[1]) < 0.05
    assert sim.events.nan_commands == 20


def test_silent_controller_stops_the_robot_and_the_run_says_so():
    config = StackConfig(silent_after=2.0, time_limit=5.0)
    score, trace = run_barn(np.zeros((30, 30), np.uint8), 5.0, config=config)
    assert score.timeout and not score.success and score.cmd_timeouts == 1
    last = trace.trajectory[-20:, :2]  # the last second: standing still
    assert np.ptp(last[:, 0]) < 0.02 and np.ptp(last[:, 1]) < 0.02
