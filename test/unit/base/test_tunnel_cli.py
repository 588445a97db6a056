"""maru-base-plan --planner tunnel on the paper's house map."""

from __future__ import annotations

import json

from maru_planner.base import cli
from maru_planner.paths import config_path


def test_cli_tunnel_on_the_house(tmp_path):
    out, png = tmp_path / "plan.json", tmp_path / "plan.png"
    code = cli.main(
        [
            "--map",
            str(config_path("maps", "house_250.yaml")),
            "--planner",
            "tunnel",
            "--start",
            "2.5",
            "21",
            "0",
            "--goal",
            "22",
            "3",
            "0",
            "--footprint",
            "disc:0.25",
            "--json",
            str(out),
            "--png",
            str(png),
        ]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert data["success"] and data["stats"]["deciding_stage"].startswith("tunnel")
    assert data["path"][0][:2] == [2.5, 21.0] and data["path"][-1][:2] == [22.0, 3.0]
    assert png.stat().st_size > 1000


def test_cli_tunnel_bad_parameter_is_an_input_error(tmp_path):
    code = cli.main(
        [
            "--map",
            str(config_path("maps", "house_250.yaml")),
            "--planner",
            "tunnel",
            "--start",
            "2.5",
            "21",
            "0",
            "--goal",
            "22",
            "3",
            "0",
            "--param",
            "k2=0.5",
        ]
    )
    assert code == 2
