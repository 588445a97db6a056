"""maru-reactive-sim as a user runs it: bad files, paths and values give one stderr line and exit 2."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO_ROOT = Path(__file__).resolve().parents[3]
GOOD_WORLD = {
    "obstacles": [{"type": "circle", "center": [1.5, 0.4], "radius": 0.2}],
    "robot": {"start": [0, 0, 0], "goal": [2, 0, 0]},
    "max_time": 20,
}


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "maru_planner.sim.cli", *args, "--quiet", "--no-arm"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=REPO_ROOT,
    )


def world_file(tmp_path: Path, data=None, text: str | None = None) -> str:
    path = tmp_path / "world.yaml"
    path.write_text(text if text is not None else yaml.safe_dump(data))
    return str(path)


def with_laser(**laser) -> dict:
    return {**GOOD_WORLD, "robot": {**GOOD_WORLD["robot"], "laser": laser}}


BAD_INPUTS = {
    "yaml syntax error": (lambda t: ["--world", world_file(t, text="robot: [unclosed")], "invalid YAML"),
    "missing world": (lambda t: ["--world", str(t / "none.yaml")], "cannot read"),
    "world is a directory": (lambda t: ["--world", str(t)], "cannot read"),
    "range_max < range_min": (
        lambda t: ["--world", world_file(t, with_laser(range_min=5.0, range_max=1.0))],
        "range_min < range_max",
    ),
    "laser value not a number": (lambda t: ["--world", world_file(t, with_laser(rate="fast"))], "robot.laser.rate"),
    "too many beams": (lambda t: ["--world", world_file(t, with_laser(resolution_deg=1e-6))], "beams"),
    "obstacles not a list": (lambda t: ["--world", world_file(t, {**GOOD_WORLD, "obstacles": 5})], "obstacles"),
    "missing map": (lambda t: ["--world", world_file(t, {**GOOD_WORLD, "map": "maps/room.yaml"})], "map"),
    "unwritable json": (lambda t: ["--world", world_file(t, GOOD_WORLD), "--json", str(t / "no" / "o.json")], "--json"),
    "png is a directory": (lambda t: ["--world", world_file(t, GOOD_WORLD), "--png", str(t)], "--png"),
    "nan max time": (lambda t: ["--world", world_file(t, GOOD_WORLD), "--max-time", "nan"], "--max-time"),
    "negative seed": (lambda t: ["--world", world_file(t, GOOD_WORLD), "--seed", "-1"], "--seed"),
    "seed not a number": (lambda t: ["--world", world_file(t, GOOD_WORLD), "--seed", "x"], "--seed"),
    "unknown strip": (lambda t: ["--world", world_file(t, GOOD_WORLD), "--strip", "elastic"], "--strip"),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_exits_2_with_one_line(case, tmp_path):
    make_args, expected = BAD_INPUTS[case]
    result = run_cli(*make_args(tmp_path))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert lines[0].startswith("maru-reactive-sim: error:") and expected in lines[0], lines[0]
    assert result.stdout == ""


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_read_only_output_directory_is_refused_before_the_run(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        result = run_cli("--world", world_file(tmp_path, GOOD_WORLD), "--json", str(locked / "o.json"))
    finally:
        locked.chmod(0o700)
    assert result.returncode == 2 and "not writable" in result.stderr and result.stdout == ""


def test_good_run_exits_0_and_help_lists_the_exit_codes(tmp_path):
    out = tmp_path / "o.json"
    result = run_cli("--world", world_file(tmp_path, GOOD_WORLD), "--json", str(out), "--no-jitter")
    assert result.returncode == 0, result.stderr
    assert json.loads(out.read_text())["outcome"] in ("goal", "collision", "timeout")
    help_text = subprocess.run(
        [sys.executable, "-m", "maru_planner.sim.cli", "--help"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=REPO_ROOT,
    ).stdout
    assert "exit codes:" in help_text and "2    bad input" in help_text
