"""The view's parts without a browser: maru-view's bad input, the panel's controls from the registry's ParamSpecs,
the robot's visual meshes, obstacles as triangles (a box's facing outward), the trajectory sampled for playback,
the plan summary, and how a screenshot is judged to show the robot."""

from __future__ import annotations

import math

import numpy as np
import pytest
import viser

from maru_planner import errors
from maru_planner.planning.planners.registry import PLANNERS
from maru_planner.planning.types import MotionResult, PlanStats, PlanStatus, set_failure
from maru_planner.robot import RobotModel
from maru_planner.runtime import RobotSource
from maru_planner.scene import Obstacle
from maru_planner.trajectory.trajectory import Trajectory
from maru_planner.web import browser, cli
from maru_planner.web.plan_view import PlanView, result_summary, trajectory_state
from maru_planner.web.planning_panel import control_value, moved_by, param_control
from maru_planner.web.robot_view import pose_of, visual_parts, wxyz_position
from maru_planner.web.scene_edit import new_obstacle
from maru_planner.web.scene_view import faces_mesh, outward


@pytest.fixture(scope="module")
def server():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield server
    server.stop()


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--robot", "nope"], "unknown robot 'nope'"),
        (["--scene", "/no/such/scene.yaml"], "scene file not found"),
        (["--host", "192.0.2.1"], "cannot serve on host '192.0.2.1'"),
        (["--port", "70000"], "--port must be in [0, 65535]"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv, says, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err


def test_every_planner_parameter_gets_a_control_reading_back_its_default(server):
    for spec in PLANNERS.values():
        for param in spec.params.values():
            assert control_value(param, param_control(server.gui, param)) == param.default, (spec.id, param.name)


def test_a_control_value_is_checked_against_its_spec(server):
    specs = PLANNERS["CompiledRRTConnect"].params
    seed = param_control(server.gui, specs["seed"])
    seed.value = "17"
    assert control_value(specs["seed"], seed) == 17
    seed.value = "x"
    with pytest.raises(errors.InvalidRequest, match="seed"):
        control_value(specs["seed"], seed)
    goal_bias = PLANNERS["RRT"].params["goal_bias"]
    number = param_control(server.gui, goal_bias)
    number._impl.value = 3.0  # what a client could send past the input's range
    with pytest.raises(errors.InvalidRequest, match="goal_bias"):
        control_value(goal_bias, number)


def test_visual_meshes_hang_on_frames_of_the_planning_model():
    robot = RobotModel.from_profile("panda")
    parts = visual_parts(RobotSource(profile="panda"))
    assert len(parts) >= 10 and sum(len(p.faces) for p in parts) > 10_000
    assert all(robot.model.existFrame(p.frame) for p in parts)
    assert all(p.faces.max() < len(p.vertices) for p in parts)
    assert moved_by(robot, robot.end_effectors["hand"]) >= set(robot.groups["arm"])


def test_poses_round_trip_through_viser_quaternions():
    pose = Obstacle("o", "box", [0.1, 0.2, 0.3, 0.4, -0.5, 1.0], size=(1, 1, 1)).pose
    np.testing.assert_allclose(pose_of(*wxyz_position(pose)), pose, atol=1e-12)


def test_obstacles_become_triangles_and_bad_ones_are_refused():
    vertices, faces = faces_mesh(new_obstacle("b", "box", (0.1, 0.2, 0.3), 0.05, 0.2))
    assert faces.shape == (12, 3) and np.ptp(vertices, axis=0) == pytest.approx([0.1, 0.2, 0.3])
    assert new_obstacle("c", "cylinder", (1, 1, 1), 0.05, 0.2).dimensions == {"radius": 0.05, "length": 0.2}
    with pytest.raises(errors.InvalidScene, match="shape must be one of"):
        new_obstacle("m", "mesh", (1, 1, 1), 0.05, 0.2)
    with pytest.raises(errors.InvalidScene, match="'s'"):
        new_obstacle("s", "sphere", (1, 1, 1), -1.0, 0.2)


def test_a_box_mesh_faces_outward_whatever_the_polygons_winding():
    vertices, faces = faces_mesh(new_obstacle("b", "box", (0.1, 0.2, 0.3), 0.05, 0.2))
    scrambled = faces.copy()
    scrambled[::2] = scrambled[::2, ::-1]
    turned = outward(vertices, scrambled)
    corners = vertices[turned]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(np.einsum("ij,ij->i", normals, corners.mean(axis=1)) > 0)
    assert sorted(map(sorted, turned.tolist())) == sorted(map(sorted, faces.tolist()))  # the same triangles


def test_the_robot_is_shown_when_most_of_its_pixels_look_as_with_it():
    hidden = np.full((40, 60, 3), 255, dtype=np.uint8)
    hidden[30:, :] = 200  # the floor
    shown = hidden.copy()
    shown[10:20, 20:30] = (90, 90, 90)  # the robot
    notice = hidden.copy()
    notice[0:8, 0:60] = (30, 30, 30)  # a panel over the canvas, in both images
    robot = browser.robot_region(shown, hidden, browser.changed(shown, hidden))
    assert robot.box == (20, 10, 10, 10) and robot.share == pytest.approx(100 / 2400)
    assert browser.robot_shown(robot.shown, robot) == 1.0 and browser.robot_shown(robot.hidden, robot) == 0.0
    half = robot.hidden.copy()
    half[:5] = robot.shown[:5]
    assert browser.robot_shown(half, robot) == pytest.approx(0.5)
    cut = (slice(10, 20), slice(20, 30))
    assert browser.robot_shown(notice[cut], robot) == 0.0  # something drawn elsewhere is not the robot


def test_playback_interpolates_the_trajectory_joints_only():
    trajectory = Trajectory(["b"], np.array([0.0, 1.0]), np.array([[0.0], [2.0]]), np.zeros((2, 1)), np.zeros((2, 1)))
    start = np.array([5.0, 0.0, 7.0])
    np.testing.assert_allclose(trajectory_state(trajectory, start, np.array([1]), 0.25), [5.0, 0.5, 7.0])
    np.testing.assert_allclose(trajectory_state(trajectory, start, np.array([1]), 9.0), [5.0, 2.0, 7.0])


def test_the_summary_shows_clearance_or_the_one_line_failure():
    stats = PlanStats(planner_id="RRTConnect", certified=True, min_clearance=0.0123, total_time=0.05)
    ok = MotionResult(PlanStatus.SUCCESS, "found", stats=stats)
    assert "clearance 12.3 mm" in result_summary(ok) and "certified: yes" in result_summary(ok)
    failed = MotionResult(PlanStatus.SUCCESS)
    set_failure(failed, errors.NoIKSolution("no IK solution for [hand]"))
    assert result_summary(failed) == "**NO_IK_SOLUTION**: no IK solution for [hand]"
    assert not math.isfinite(PlanStats().min_clearance) and "n/a" in result_summary(MotionResult(PlanStatus.SUCCESS))


def test_a_node_can_show_its_scene_start_and_plans_on_a_plan_view():
    view = PlanView.serve(RobotSource(profile="maru1"), port=0)
    try:
        assert view.url.startswith("http://127.0.0.1:")
        scene = {
            "obstacles": [{"name": "crate", "type": "box", "size": [0.2, 0.2, 0.2], "pose": {"xyz": [0.6, 0, 0.9]}}],
            "attached": [{"name": "cup", "type": "cylinder", "radius": 0.03, "length": 0.1, "link": "r_hand"}],
        }
        view.show_scene(scene)
        assert view.scene_view.obstacle_names == ["crate"] and list(view.scene_view.scene.attached) == ["cup"]
        view.show_start({"waist_yaw": 0.3})
        assert view.robot_view.q[view.robot.joint_indices(["waist_yaw"])] == pytest.approx(0.3)
        positions = np.array([[0.3, 0.0], [0.0, 0.4]])
        trajectory = Trajectory(["waist_yaw", "r_arm_j1"], np.array([0.0, 0.2]), positions, *[np.zeros((2, 2))] * 2)
        view.show_result(MotionResult(PlanStatus.SUCCESS, "found", trajectory=trajectory))
        assert view.wait_played(timeout=10.0)
        np.testing.assert_allclose(view.robot_view.q[view.robot.joint_indices(["waist_yaw", "r_arm_j1"])], [0.0, 0.4])
        failed = MotionResult(PlanStatus.SUCCESS)
        set_failure(failed, errors.NoPath("no path within 1 s"))
        view.show_result(failed)
        assert view.status.content == "**PLANNING_FAILED**: no path within 1 s"
    finally:
        view.close()


def test_a_scene_attaching_to_an_unknown_link_is_refused_before_serving(tmp_path, capsys):
    scene = tmp_path / "bad.yaml"
    scene.write_text("attached:\n  - {name: cup, type: sphere, radius: 0.03, link: no_such_link}\n")
    assert cli.main(["--scene", str(scene), "--port", "0"]) == 2
    assert "'no_such_link' is not a link of maru1" in capsys.readouterr().err
