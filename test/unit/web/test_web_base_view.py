"""The base side of the view: a reactive run replayed from a recorded bag (poses, laser points in the world, path,
goal), drawn and scrubbed on a viser server; a bad bag or map is one line and exit 2."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest
import viser

from maru_planner.paths import config_path
from maru_planner.web import cli
from maru_planner.web.base_view import BaseView, read_base_run
from maru_planner.web.serving import serve

BAG = str(Path(__file__).resolve().parents[2] / "data" / "reactive_goal_behind_obstacle")


@pytest.fixture(scope="module")
def run():
    return read_base_run(BAG)


def test_a_bag_gives_poses_scans_in_the_world_path_and_goal(run):
    assert len(run.times) == len(run.poses) > 10 and np.all(np.diff(run.times) >= 0)
    assert len(run.scan_points) == len(run.scan_times) > 10
    assert run.path.shape[1] == 2 and run.goal is not None
    np.testing.assert_allclose(run.path[-1], run.goal)
    # laser points lie within the laser's range of the base that saw them
    t = float(run.scan_times[len(run.scan_times) // 2])
    points, pose = run.points_at(t), run.pose_at(t)
    assert len(points) and np.all(np.linalg.norm(points - pose[:2], axis=1) < 10.5)


def test_the_view_moves_the_base_with_the_scrubber(run):
    server = serve("127.0.0.1", 0)
    try:
        view = BaseView(server, run)
        t = 0.5 * run.duration
        view.show_time(t)
        np.testing.assert_allclose(view.base.position[:2], run.pose_at(t)[:2], atol=1e-6)
        assert len(view.scan.points) == max(len(run.points_at(t)), 1)
        assert isinstance(view.scan, viser.PointCloudHandle)
    finally:
        server.stop()


@pytest.mark.parametrize(
    ("argv", "says"),
    [(["--bag", "/no/such/bag"], "/no/such/bag"), (["--bag", BAG, "--map", "/no/such/map.yaml"], "--map")],
)
def test_a_bad_bag_or_map_is_one_line_and_exit_2(argv, says, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err


def test_a_map_is_drawn_under_the_run(run):
    args = argparse.Namespace(bag=BAG, map=str(config_path("maps/paper002_easy.yaml")), host="127.0.0.1", port=0,
                              robot="maru1", scene="", collision_model="spheres")  # fmt: skip
    view = cli.base_view(args)
    try:
        assert view.map_cells > 100
    finally:
        view.server.stop()
