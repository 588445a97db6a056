"""maru-base-plan --world for the biped planners (both spellings of the planner id)."""

from __future__ import annotations

import json

import pytest

from maru_planner.base import cli
from maru_planner.paths import config_path

NARROW = str(config_path("worlds", "biped", "corridor_narrow.yaml"))


@pytest.mark.parametrize("planner,expected", [("biped-wall", 0), ("biped_wall", 0), ("biped-track", 1)])
def test_world_option(tmp_path, planner, expected):
    out = tmp_path / "plan.json"
    code = cli.main(["--world", NARROW, "--planner", planner, "--json", str(out)])
    assert code == expected
    data = json.loads(out.read_text())
    assert data["success"] == (expected == 0)
    if expected == 1:
        assert "K =" in data["message"]  # K > L: track following cannot turn here


def test_world_picture_and_explicit_poses(tmp_path):
    png = tmp_path / "wall.png"
    code = cli.main(
        [
            "--world",
            NARROW,
            "--planner",
            "biped-wall",
            "--start",
            "0.4",
            "1.0",
            "0",
            "--goal",
            "2.5",
            "1.0",
            "0",
            "--png",
            str(png),
        ]
    )
    assert code == 0 and png.stat().st_size > 1000


def test_missing_world_and_map_are_input_errors(tmp_path):
    assert cli.main(["--world", str(tmp_path / "none.yaml"), "--planner", "biped-track"]) == 2
    assert cli.main(["--planner", "tunnel", "--start", "0", "0", "0", "--goal", "1", "1", "0"]) == 2
