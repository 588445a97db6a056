"""Adding a base planner is one registry entry: a toy registered from outside the package shows up in the
CLI, the node (a real PlanBasePath call: ``test/ros/test_base_planner_node.py``) and the parametrised planner tests,
with no other edit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from maru_planner.base import registry
from maru_planner.base.astar import GridAStarPlanner
from maru_planner.params import ParamSpec
from maru_planner.paths import config_path

TEST_DIR = Path(__file__).resolve().parents[2]
REPO = TEST_DIR.parent
TOY = "toy_straight"


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(TEST_DIR), env.get("PYTHONPATH")]))
    return env


def run_toy(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "toy_base_planner", *args],
        capture_output=True,
        text=True,
        cwd=REPO,
        env=_env(),
        timeout=180,
    )


def test_toy_appears_in_the_cli_help_and_plans():
    help_text = run_toy("cli", "--help")
    assert help_text.returncode == 0 and f"  {TOY}: toy: a point robot" in help_text.stdout
    assert "samples_per_cell (default 2)" in help_text.stdout
    out = run_toy(
        "cli",
        "--map",
        str(config_path("maps", "paper002_easy.yaml")),
        "--planner",
        TOY,
        "--start",
        "1",
        "2",
        "0",
        "--goal",
        "2",
        "2",
        "0",
        "--param",
        "samples_per_cell=3",
    )
    assert out.returncode == 0, out.stderr
    assert "solved: straight segment is free" in out.stderr
    bad = run_toy(
        "cli",
        "--map",
        str(config_path("maps", "paper002_easy.yaml")),
        "--planner",
        TOY,
        "--start",
        "1",
        "2",
        "0",
        "--goal",
        "2",
        "2",
        "0",
        "--param",
        "headings=32",
    )
    assert bad.returncode == 2 and "no parameter 'headings'" in bad.stderr


def test_toy_runs_through_the_parametrised_planner_tests():
    cmd = [
        sys.executable,
        "-m",
        "pytest",
        "-p",
        "no:cacheprovider",
        "-p",
        "toy_base_planner",
        "-q",
        "-k",
        TOY,
        str(TEST_DIR / "unit" / "base" / "test_base_planners.py"),
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO, env=_env(), timeout=600)
    assert out.returncode == 0, out.stdout[-3000:]
    summary = out.stdout.strip().splitlines()[-1]
    assert " passed" in summary and "failed" not in summary and "error" not in summary
    assert int(summary.split(" passed")[0].split()[-1]) >= 6  # the tests that iterate the registry


def test_spec_capabilities_match_their_parameters():
    with pytest.raises(ValueError, match="needs_headings goes with a 'headings' parameter"):
        registry.BasePlannerSpec("x", "x", GridAStarPlanner, {}, frozenset({registry.NEEDS_HEADINGS}))
    with pytest.raises(ValueError, match="world_3d"):
        registry.BasePlannerSpec("x", "x", GridAStarPlanner, {"world": ParamSpec("world", "")}, frozenset())
    with pytest.raises(ValueError, match="unknown capabilities"):
        registry.BasePlannerSpec("x", "x", GridAStarPlanner, {}, frozenset({"flies"}))
    with pytest.raises(ValueError, match="already registered"):
        registry.register(registry.spec("astar"))


def test_footprint_only_for_planners_that_use_it():
    entry = registry.BasePlannerSpec("no_fp", "point robot", GridAStarPlanner)
    registry.SPECS[entry.id] = entry
    try:
        planner = registry.make_planner("no_fp", np.array([[5.0, 5.0], [-5.0, 5.0], [0.0, -5.0]]))
        assert planner.robot_radius == 0.0  # the footprint was not handed over
    finally:
        del registry.SPECS[entry.id]


def test_warm_up_runs_every_grid_kernel_including_weighted_a_star(monkeypatch):
    """The warm-up's open grid needs no MSPP guide path past a narrow passage: it runs the weighted A* kernel itself,
    so no request compiles it."""
    from maru_planner.base import astar, registry

    calls = []
    real = astar._astar_kernel
    monkeypatch.setattr(astar, "_astar_kernel", lambda *args: calls.append(args[6]) or real(*args))
    registry.warm_up()
    assert 1 in calls  # cost mode 1 (added cost): the variant MSPP's guide path takes
    assert 2 in calls  # cost mode 2 (weighted length): cost-aware A*
