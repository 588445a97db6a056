"""maru-barn --through-ros end to end, as a user runs it: mujoco_sim_node, base_planner_node and the unchanged
reactive_node as processes in lock-step on one quick BARN world; the JSON and the picture it writes (issue 38).
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from maru_planner.barn.cli import main

WORLD = 162  # one of the quickest public worlds (about 8 s of sim time, 81 lock-step periods)


@pytest.fixture(scope="module")
def barn_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("barn_ros")
    json_path, png_path = out / "run.json", out / "run.png"
    command = [sys.executable, "-m", "maru_planner.barn.cli", "--world", str(WORLD), "--through-ros"]
    command += ["--json", str(json_path), "--png", str(png_path)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    return done, json_path, png_path


def test_through_ros_run_exits_0_and_says_so_on_stderr(barn_run):
    done, _, _ = barn_run
    assert done.returncode == 0, done.stderr[-2000:]
    assert f"world_{WORLD} seed 0: success" in done.stderr
    summary = json.loads(done.stdout)
    assert summary["runs"] == 1 and summary["success_rate"] == 1.0


def test_through_ros_json_is_a_scored_success(barn_run):
    done, json_path, _ = barn_run
    assert done.returncode == 0, done.stderr[-2000:]
    payload = json.loads(json_path.read_text())
    assert payload["world"] == f"world_{WORLD}"
    (run,) = payload["runs"]
    assert run["success"] is True and run["collision"] is False and run["timeout"] is False
    assert run["metric"] > 0.0 and run["optimal_time_s"] > 0.0
    assert run["optimal_time_s"] <= run["time_s"] < 100.0  # OT is the path at 2 m/s; the base does 1.2 at most
    clipped = min(max(run["time_s"], 2 * run["optimal_time_s"]), 8 * run["optimal_time_s"])
    assert run["metric"] == pytest.approx(run["optimal_time_s"] / clipped, abs=1e-3)
    assert 0.0 < run["min_clearance_m"] < 5.0
    assert run["replans"] >= 2 and run["cmd_timeouts"] == 0 and run["nan_commands"] == 0
    assert run["sim_time_s"] >= run["time_s"]


def test_through_ros_png_is_a_picture(barn_run):
    done, _, png_path = barn_run
    assert done.returncode == 0, done.stderr[-2000:]
    data = png_path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_bad_grid_through_ros_is_one_line_exit_2_before_any_node_starts(tmp_path, capsys):
    path = tmp_path / "grid.npy"
    np.save(path, np.zeros((30, 29), np.uint8))
    assert main(["--grid", str(path), "--through-ros", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "shape" in err and "Traceback" not in err
