"""What makes the view start sooner and the base side live: the robot's simplified meshes kept on disk (and dropped
when a mesh file changes), planner parameter folders made only when chosen, a BARN world as one instanced mesh, and
the live base view's setters; ``maru-view --barn N`` refuses a world that does not exist."""

from __future__ import annotations

import os

import numpy as np
import pytest
import viser

from maru_planner.physics import barn_world
from maru_planner.planning.planners.registry import PLANNERS
from maru_planner.robot import RobotModel
from maru_planner.runtime import RobotSource
from maru_planner.web import cli, robot_view
from maru_planner.web.base_live import LiveBaseView, segments
from maru_planner.web.planning_panel import PlanningPanel


@pytest.fixture(scope="module")
def server():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield server
    server.stop()


def test_visual_parts_are_kept_on_disk_and_read_again_until_a_mesh_changes(tmp_path, monkeypatch):
    monkeypatch.setenv("MARU_PLANNER_CACHE", str(tmp_path))
    source = RobotSource(profile="maru1")
    fresh = robot_view.visual_parts(source)
    path = robot_view.parts_cache_path(*robot_view.source_files(source))
    assert path.is_file() and path.is_relative_to(tmp_path)
    kept = robot_view.visual_parts(source)
    assert [p.frame for p in kept] == [p.frame for p in fresh] and [p.color for p in kept] == [p.color for p in fresh]
    for a, b in zip(kept, fresh, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_allclose(a.local, b.local)
    mesh = tmp_path / "part.stl"
    mesh.write_text("solid x\nendsolid x\n")
    robot_view._save_parts(path, fresh[:1], [str(mesh)])
    assert len(robot_view._load_parts(path) or []) == 1
    os.utime(mesh, ns=(1, 1))  # the mesh changed since it was read
    assert robot_view._load_parts(path) is None
    path.write_bytes(b"not an npz")
    assert robot_view._load_parts(path) is None
    assert len(robot_view.visual_parts(source)) == len(fresh)  # read again and kept again


def test_a_planners_parameter_folder_is_made_when_it_is_chosen(server):
    panel = PlanningPanel(server, RobotModel.from_profile("maru1"), lambda: None)
    assert list(panel.params) == ["CompiledRRTConnect"]
    other = next(p for p, spec in PLANNERS.items() if spec.params and p != "CompiledRRTConnect")
    panel.planner.value = other
    assert panel.planner_params() == {}  # its controls exist and read back the registry's defaults
    assert set(panel.params[other]) == set(PLANNERS[other].params)
    assert panel._folders[other].visible and not panel._folders["CompiledRRTConnect"].visible


def test_the_live_base_view_draws_a_barn_world_and_follows_the_run(server):
    if not (barn_world.barn_dir() / "grid_files" / "grid_0.npy").is_file():
        pytest.skip(f"no BARN data in {barn_world.barn_dir()} (set MARU_BENCHMARKS_DIR)")
    grid = barn_world.world_grid(0)
    view = LiveBaseView(server, barn=grid)
    assert view.obstacles == len(barn_world.cylinder_centres(grid)) > 100
    view.show_scan(np.ones((3, 2)), in_base=True)
    assert view.counts["scans"] == 0  # no pose yet: nowhere to put base-frame points
    view.show_pose(-2.0, 3.0, np.pi / 2)
    view.show_scan(np.array([[1.0, 0.0]]), in_base=True)
    np.testing.assert_allclose(view.scan_points, [[-2.0, 4.0]], atol=1e-12)
    view.show_pose(-2.0, 3.01, np.pi / 2)  # moved less than TRACE_STEP
    view.show_pose(-2.0, 3.2, np.pi / 2)
    assert len(view.trace) == 2
    view.show_strip(np.array([[0.0, 0.0], [1.0, 0.0]]))
    view.show_path(np.zeros((0, 2)))
    assert "1 paths" in view.summary.content and segments(np.zeros((1, 2)), 0.0).shape == (1, 2, 3)


def test_a_barn_world_out_of_range_is_one_line_and_exit_2(capsys):
    assert cli.main(["--barn", "300", "--port", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert "BARN world must be an integer 0..299" in err and "\n" not in err
