"""maru-base-plan on hostile input: one stderr line, a documented non-zero exit code, never a traceback."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from maru_planner.base.cli import EXIT_BAD_INPUT, EXIT_NO_PATH, EXIT_OUTPUT, EXIT_SOLVED
from maru_planner.paths import config_path

REPO = Path(__file__).resolve().parents[2]
MEDIUM = str(config_path("maps", "paper002_medium.yaml"))
POSES = ["--start", "1", "2", "0", "--goal", "5", "2", "0"]


def run_cli(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "maru_planner.base.cli", *args],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=120,
        env=env,
    )


def assert_one_line_error(out: subprocess.CompletedProcess, code: int, needle: str) -> None:
    assert out.returncode == code, (out.returncode, out.stderr)
    assert "Traceback" not in out.stderr and "Traceback" not in out.stdout
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("maru-base-plan: "), out.stderr
    assert needle in lines[0], lines[0]


def write_map(directory: Path, yaml_text: str, pixels: np.ndarray | None = None) -> str:
    if pixels is not None:
        Image.fromarray(pixels).save(directory / "m.pgm")
    (directory / "m.yaml").write_text(yaml_text)
    return str(directory / "m.yaml")


GOOD_YAML = "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n"
SMALL = np.full((40, 60), 254, dtype=np.uint8)


@pytest.mark.parametrize(
    "yaml_text, needle",
    [
        ("image: m.pgm\nresolution: [0.1\n", "not valid YAML"),
        ("image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 2\n", "occupied_thresh must be in [0, 1]"),
        ("image: m.pgm\nresolution: -0.1\norigin: [0, 0, 0]\n", "resolution"),
        ("image: m.pgm\nresolution: abc\norigin: [0, 0, 0]\n", "resolution must be a finite number"),
        ("image: m.pgm\nresolution: 0.1\norigin: [0, 0]\nmode: fancy\n", "mode"),
        ("image: m.pgm\nresolution: 0.1\norigin: [x, 0, 0]\n", "origin"),
        ("image: m.pgm\nresolution: 0.1\n", "missing key 'origin'"),
        ("- just a list\n", "not a map_server YAML mapping"),
        ("image: none.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n", "none.pgm"),
    ],
)
def test_bad_map_files(tmp_path, yaml_text, needle):
    path = write_map(tmp_path, yaml_text, SMALL)
    assert_one_line_error(run_cli("--map", path, *POSES), EXIT_BAD_INPUT, needle)


def test_an_8000_square_pgm_is_refused_before_decoding(tmp_path):
    with open(tmp_path / "m.pgm", "wb") as f:
        f.write(b"P5\n8000 8000\n255\n")
        f.truncate(f.tell() + 8000 * 8000)
    path = write_map(tmp_path, GOOD_YAML)
    assert_one_line_error(run_cli("--map", path, *POSES), EXIT_BAD_INPUT, "8000 x 8000 cells is over the limit")


def test_an_image_that_is_not_an_image(tmp_path):
    (tmp_path / "m.pgm").write_text("not a picture")
    path = write_map(tmp_path, GOOD_YAML)
    assert_one_line_error(run_cli("--map", path, *POSES), EXIT_BAD_INPUT, "m.pgm")


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--map", "/no/such/map.yaml", *POSES], "No such file"),
        (["--world", "/no/such/world.yaml", "--planner", "biped_wall"], "not found"),
        (["--map", MEDIUM, *POSES, "--footprint", "rect:-1:0.5"], "length and width > 0"),
        (["--map", MEDIUM, *POSES, "--footprint", "disc:0"], "radius > 0"),
        (["--map", MEDIUM, *POSES, "--footprint", "1,2 3"], "--footprint"),
        (["--map", MEDIUM, *POSES, "--footprint", "0,0 1,0"], "footprint"),
        (["--map", MEDIUM, *POSES, "--planner", "rrt_star"], "unknown base planner 'rrt_star'"),
        (["--map", MEDIUM, *POSES, "--param", "headings"], "expected key=value"),
        (["--map", MEDIUM, *POSES, "--param", "headings=-3"], "'headings' = -3 is outside"),
        (["--map", MEDIUM, *POSES, "--param", "nope=1"], "no parameter 'nope'"),
        (["--map", MEDIUM, *POSES, "--time-limit", "nan"], "--time-limit"),
        (["--map", MEDIUM, "--start", "1", "2", "x", "--goal", "5", "2", "0"], "invalid float value"),
        (["--map", MEDIUM], "--start and --goal are required"),
        (["--start", "0", "0", "0", "--goal", "1", "1", "0"], "--map is required"),
        (["--map", MEDIUM, *POSES, "--json", "/no/such/dir/out.json"], "does not exist"),
        (["--map", MEDIUM, *POSES, "--png", "/"], "is a directory"),
        (
            ["--map", MEDIUM, "--world", str(config_path("worlds", "biped", "corridor_wide.yaml")), *POSES],
            "--world needs a world_3d planner",
        ),
    ],
)
def test_bad_arguments_and_files(args, needle):
    assert_one_line_error(run_cli(*args), EXIT_BAD_INPUT, needle)


def test_unwritable_output_directory(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    if os.access(locked, os.W_OK):
        pytest.skip("running as a user who can write anywhere")
    out = run_cli("--map", MEDIUM, *POSES, "--json", str(locked / "out.json"))
    assert_one_line_error(out, EXIT_BAD_INPUT, "not writable")


def test_huge_world_bounds(tmp_path):
    world = tmp_path / "w.yaml"
    world.write_text("bounds: [0, 0, 1000000, 1000000]\nstart: [1, 1, 0]\ngoal: [2, 2, 0]\nobstacles: []\n")
    out = run_cli("--world", str(world), "--planner", "biped_wall")
    assert_one_line_error(out, EXIT_BAD_INPUT, "cells, over the limit")


def test_help_documents_the_exit_codes_and_every_planner():
    out = run_cli("--help")
    assert out.returncode == 0
    assert "exit codes:" in out.stdout and "bad input" in out.stdout
    for planner_id in ("astar", "se2", "mspp", "mspp_local", "tunnel", "biped_track", "biped_wall"):
        assert f"  {planner_id}: " in out.stdout


def test_outcomes_have_their_exit_codes(tmp_path):
    out = tmp_path / "o.json"
    assert run_cli("--map", MEDIUM, *POSES, "--json", str(out)).returncode == EXIT_SOLVED
    assert json.loads(out.read_text())["status"] == "solved"
    blocked = run_cli("--map", MEDIUM, *POSES, "--planner", "astar")
    assert blocked.returncode == EXIT_NO_PATH and "Traceback" not in blocked.stderr
    timed_out = run_cli(
        "--map",
        str(config_path("maps", "house_250.yaml")),
        "--planner",
        "se2",
        "--start",
        "2.5",
        "21",
        "0",
        "--goal",
        "22",
        "3",
        "0",
        "--time-limit",
        "0.001",
    )
    assert timed_out.returncode == EXIT_NO_PATH and "timed out" in timed_out.stderr


def test_output_that_fails_while_writing(tmp_path):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    out = run_cli("--map", MEDIUM, *POSES, "--json", "/dev/full")
    assert out.returncode == EXIT_OUTPUT and "Traceback" not in out.stderr
    assert out.stderr.strip().splitlines()[-1].startswith("maru-base-plan: cannot write the output")
