"""Biped planning among 3-D obstacles (paper 004): mapping (eq. 1-3), turning rule (eq. 4), both planners."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import ndimage

from maru_planner.base import registry
from maru_planner.base.astar import astar_2d
from maru_planner.base.biped import (
    BipedRobot,
    Box3D,
    TrackFollowingPlanner,
    VirtualWallPlanner,
    classify,
    load_world,
    map_3d_to_2d,
    turn_allowed,
    wheeled_map,
    world_from_dict,
)
from maru_planner.base.biped.geometry import RectangleChecker
from maru_planner.base.biped.mapping import side_of_line
from maru_planner.base.biped.planners import biped_track, biped_wall
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import PlanStatus as res
from maru_planner.errors import InvalidRequest, InvalidScene, TooLarge
from maru_planner.paths import config_path

ROBOT = BipedRobot(
    gait_length=0.4, gait_width=0.36, body_left=0.25, body_right=0.25, step_height=0.06, body_bottom=0.45, height=1.2
)


def world(name):
    return load_world(config_path("worlds", "biped", f"{name}.yaml"))


@pytest.mark.parametrize(
    "z,kind",
    [
        ((0.0, 0.04), "steppable"),
        ((0.0, 0.3), "line"),
        ((0.6, 0.8), "virtual"),
        ((0.0, 2.0), "line+virtual"),
        ((1.5, 2.0), "overhead"),
    ],
)
def test_classify_by_height_bands(z, kind):
    assert classify(Box3D("b", (0, 0), (1, 1), z), ROBOT) == kind


def _one_box_world(z, robot=None, center=(1.0, 1.0)):
    data = {
        "resolution": 0.01,
        "bounds": [0, 0, 2, 2],
        "start": [0.2, 1.0, 0.0],
        "goal": [1.8, 1.0, 0.0],
        "obstacles": [{"name": "box", "center": list(center), "size": [0.2, 0.2], "z": list(z)}],
        "robot": robot or {"gait_length": 0.4, "gait_width": 0.36, "body_width": 0.5},
    }
    return world_from_dict(data)


def _extent(mask, axis_rows: bool, res=0.01):
    rows, cols = np.nonzero(mask)
    idx = rows if axis_rows else cols
    return (idx.max() - idx.min() + 1) * res


def test_symmetric_clearance_eq1_grows_virtual_obstacles_only():
    line_only = map_3d_to_2d(_one_box_world((0.0, 0.3)))
    assert line_only.virtual.sum() == 0
    assert _extent(line_only.line, False) == pytest.approx(0.2, abs=0.011)
    body = map_3d_to_2d(_one_box_world((0.0, 2.0)))
    overhang = (0.5 - 0.36) / 2  # eq. 1: (w_r - w_k) / 2
    assert body.growth["box"] == pytest.approx(overhang)
    assert _extent(body.virtual, False) == pytest.approx(0.2 + 2 * overhang, abs=0.021)
    assert _extent(body.line, False) == pytest.approx(0.2, abs=0.011)


def test_asymmetric_clearance_eq2_eq3_depends_on_the_side_of_line_s():
    robot = {"gait_length": 0.4, "gait_width": 0.36, "body_left": 0.35, "body_right": 0.18}
    left = map_3d_to_2d(_one_box_world((0.0, 2.0), robot, center=(1.0, 1.5)))  # left of S (start -> goal, +x)
    right = map_3d_to_2d(_one_box_world((0.0, 2.0), robot, center=(1.0, 0.5)))
    d_left = 0.35 + 0.18 - (0.18 + 0.36 / 2)  # eq. 3: w_r - (delta_MR + w_k/2)
    d_right = 0.35 + 0.18 - (0.35 + 0.36 / 2)  # eq. 2: w_r - (delta_ML + w_k/2), clipped at 0
    assert left.growth["box"] == pytest.approx(d_left)
    assert right.growth["box"] == pytest.approx(max(0.0, d_right))
    assert _extent(left.virtual, True) > _extent(right.virtual, True) + 0.2


def test_side_of_line():
    line = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    np.testing.assert_array_equal(
        side_of_line(np.array([[0.5, 0.3], [0.5, -0.3], [0.7, 0.5], [1.3, 0.5]]), line), [1, -1, 1, -1]
    )


def test_turning_rule_eq4():
    k = ROBOT.corner_distance
    assert turn_allowed(math.pi / 2, ROBOT, k)[0]
    assert not turn_allowed(math.pi / 2, ROBOT, k - 0.01)[0]
    thin = BipedRobot(gait_length=1.0, gait_width=0.2)
    small = math.radians(10)
    ok, need = turn_allowed(small, thin, 0.2)
    assert ok and need == pytest.approx(thin.corner_distance * math.sin(small + math.atan2(0.2, 1.0)))
    assert not turn_allowed(math.radians(100), thin, 0.2)[0]  # >= pi/2 needs K <= L


def _assert_walkable(m, robot, path):
    checker = RectangleChecker(m.occupied, m.resolution / 2, m.origin, robot.gait_length, robot.gait_width)
    checker.occupied = np.kron(m.occupied, np.ones((2, 2), dtype=bool))  # an independent, finer check
    assert not checker.sweep_collides(path, m.resolution / 4, math.radians(1))


def test_k_le_l_scene_both_planners_pass():
    w = world("corridor_wide")
    m = map_3d_to_2d(w)
    assert m.classes["door_threshold"] == "steppable" and m.classes["shoe_box"] == "line"
    for planner in (TrackFollowingPlanner(w.robot), VirtualWallPlanner(w.robot)):
        plan = planner.plan(m, w.start, w.goal)
        assert plan.status == res.SOLVED, plan.message
        np.testing.assert_allclose(plan.path[0], w.start, atol=1e-9)
        np.testing.assert_allclose(plan.path[-1][:2], w.goal[:2], atol=1e-9)
        assert abs(math.remainder(plan.path[-1][2] - w.goal[2], 2 * math.pi)) < 1e-6
        _assert_walkable(m, w.robot, plan.path)


def test_k_gt_l_scene_only_the_virtual_wall_passes():
    w = world("corridor_narrow")
    m = map_3d_to_2d(w)
    assert w.robot.corner_distance > 0.22 >= w.robot.gait_width / 2
    track = TrackFollowingPlanner(w.robot).plan(m, w.start, w.goal)
    assert track.status == res.NO_PATH and "K =" in track.message
    wall = VirtualWallPlanner(w.robot).plan(m, w.start, w.goal)
    assert wall.status == res.SOLVED, wall.message
    _assert_walkable(m, w.robot, wall.path)
    trace = wall.layers["trace"]
    assert len(trace["theta_cw"]) == len(trace["xi"]) and any(any(flags) for flags in trace["widening"])
    assert all(abs(x) <= math.radians(90) for x in trace["xi"])


def test_a_wheeled_robot_of_the_body_width_cannot_pass_the_narrow_scene():
    w = world("corridor_narrow")
    occ = wheeled_map(w)
    grid_inflated = np.asarray(occ)
    grown = ndimage.distance_transform_edt(~grid_inflated) * w.resolution <= w.robot.body_width / 2
    m = map_3d_to_2d(w)
    s, g = m.world_to_cell(*w.start[:2]), m.world_to_cell(*w.goal[:2])
    assert len(astar_2d(grown, s, g).path) == 0


def test_virtual_wall_is_deterministic_and_damps_oscillation():
    w = world("corridor_wide")
    m = map_3d_to_2d(w)
    a = VirtualWallPlanner(w.robot).plan(m, w.start, w.goal)
    b = VirtualWallPlanner(w.robot).plan(m, w.start, w.goal)
    np.testing.assert_array_equal(a.path, b.path)
    planner = VirtualWallPlanner(w.robot)
    trace = {"theta_cw": [0.2, 0.3, 0.2], "theta_ccw": [0.3, 0.2, 0.3]}
    assert planner._damping(trace, xi=0.1, prev_xi=-0.1, damping=1) == 2  # eq. 12: c counts repeats
    assert planner._damping(trace, xi=0.1, prev_xi=0.1, damping=3) == 1


def test_start_in_obstacle_and_unknown_parameters():
    w = world("corridor_wide")
    m = map_3d_to_2d(w)
    inside = (2.5, 0.3, 0.0)
    assert TrackFollowingPlanner(w.robot).plan(m, inside, w.goal).status == res.START_OCCUPIED
    assert VirtualWallPlanner(w.robot).plan(m, w.start, (9.0, 9.0, 0.0)).status == res.GOAL_OUTSIDE_MAP
    with pytest.raises(ValueError):
        VirtualWallPlanner(w.robot, safety=1.5)
    with pytest.raises(ValueError):
        TrackFollowingPlanner(w.robot, nope=1)


@pytest.mark.parametrize(
    "patch,needle",
    [
        ({"bounds": [0, 0, -1, 1]}, "bounds"),
        ({"obstacles": [{"name": "x", "center": [0, 0], "size": [1, 1], "z": [1, 0]}]}, "z"),
        ({"robot": {"gait_width": -1}}, "gait_width"),
        ({"robot": {"wheels": 4}}, "wheels"),
    ],
)
def test_world_loader_names_what_is_wrong(patch, needle):
    data = {"bounds": [0, 0, 1, 1], "obstacles": []}
    data.update(patch)
    with pytest.raises(InvalidScene, match=needle):
        world_from_dict(data)


def test_load_world_missing_file(tmp_path):
    with pytest.raises(InvalidScene, match="not found"):
        load_world(tmp_path / "nope.yaml")


def test_grid_planner_with_a_world_file_and_with_a_plain_grid():
    w = world("corridor_wide")
    plan = biped_track(None, world="worlds/biped/corridor_wide.yaml").plan(None, w.start, w.goal, time_limit=10.0)
    assert plan.success and plan.stats.mapping == "3d_world"
    grid = map_3d_to_2d(w).to_occupancy_grid()
    footprint = np.array([[0.2, 0.18], [-0.2, 0.18], [-0.2, -0.18], [0.2, -0.18]])
    plan = biped_wall(footprint).plan(grid, w.start, w.goal)
    assert plan.success and plan.stats.mapping == "grid"
    assert biped_wall(footprint).plan(None, w.start, w.goal).status == res.INVALID_REQUEST
    with pytest.raises(InvalidScene):
        biped_track(None, world="no/such/world.yaml")
    with pytest.raises(InvalidRequest, match="headings"):  # biped planners take no headings to ignore
        biped_track(None, world="worlds/biped/corridor_wide.yaml", headings=32)


def test_biped_time_limit():
    w = world("corridor_narrow")
    m = map_3d_to_2d(w)
    result = VirtualWallPlanner(w.robot).plan(m, w.start, w.goal, time_limit=1e-9)
    assert result.status == res.TIMED_OUT and "timed out" in result.message


def test_asymmetric_scene_passes_only_with_the_side_dependent_clearance():
    w = world("corridor_asymmetric")
    m = map_3d_to_2d(w)
    assert m.growth["wall_north_west"] == pytest.approx(0.14) and m.growth["wall_south"] == pytest.approx(0.0)
    assert TrackFollowingPlanner(w.robot).plan(m, w.start, w.goal).success
    wide_both = dataclasses.replace(w, robot=dataclasses.replace(w.robot, body_right=w.robot.body_left))
    conservative = map_3d_to_2d(wide_both)
    assert not TrackFollowingPlanner(w.robot).plan(conservative, w.start, w.goal).success


def test_both_planners_on_a_plain_grid_map_the_house():
    house = OccupancyGrid.from_yaml(config_path("maps", "house_250.yaml"))
    footprint = np.array([[0.2, 0.18], [-0.2, 0.18], [-0.2, -0.18], [0.2, -0.18]])
    for planner_id in ("biped_track", "biped_wall"):
        plan = registry.plan(planner_id, house, (2.5, 21.0, 0.0), (22.0, 3.0, 0.0), footprint, time_limit=60.0)
        assert plan.success, (planner_id, plan.message)
        m = plan.layers["map"]
        _assert_walkable(m, BipedRobot(gait_length=0.4, gait_width=0.36, body_left=0.18, body_right=0.18), plan.path)


@pytest.mark.parametrize("bounds", [[0, 0, 1e6, 1e6], [-1e6, 0, 0, 10]])
def test_huge_world_bounds_are_refused_before_allocating(bounds):
    with pytest.raises(TooLarge, match="cells, over the limit"):
        world_from_dict({"bounds": bounds, "resolution": 0.02, "obstacles": []})


def test_too_many_obstacles_are_refused():
    boxes = [{"center": [0.5, 0.5], "size": [0.1, 0.1]}] * 10001
    with pytest.raises(InvalidScene, match="10001 obstacles"):
        world_from_dict({"bounds": [0, 0, 1, 1], "obstacles": boxes})
