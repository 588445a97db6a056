"""SE(2) A*, MSPP (ECA / BAA / full / local), registry and CLI on small maps."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from maru_planner.base import registry
from maru_planner.base.cli import main
from maru_planner.base.footprint import (
    dilate,
    footprint_cells,
    footprint_collides,
    footprint_radii,
    heading_offsets,
    rectangle,
)
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.mspp import LocalMultiStagePlanner, MultiStagePlanner
from maru_planner.base.result import PlanStatus as R
from maru_planner.base.scenes import build_all, table1
from maru_planner.base.se2 import SE2AStarPlanner, cspace_layers, search_layers
from maru_planner.errors import InvalidPlanner, InvalidRequest
from maru_planner.paths import config_path

ROBOT = rectangle(0.9, 0.3)
SCENES = build_all()


def assert_valid_path(grid, footprint, path, start, goal):
    """Every pose collision-free at its own heading, 8-adjacent cells, ends at start/goal cells."""
    assert len(path) >= 1
    cells = np.array([grid.world_to_cell(x, y) for x, y, _ in path])
    assert tuple(cells[0]) == grid.world_to_cell(*start[:2])
    assert tuple(cells[-1]) == grid.world_to_cell(*goal[:2])
    assert np.abs(np.diff(cells, axis=0)).max(initial=0) <= 1
    for (row, col), theta in zip(cells, path[:, 2], strict=True):
        assert not footprint_collides(grid.occupied, footprint, grid.resolution, row, col, theta)


def test_footprint_radii_of_centred_rectangle():
    r_in, r_out = footprint_radii(ROBOT)
    assert r_in == pytest.approx(0.15)
    assert r_out == pytest.approx(math.hypot(0.45, 0.15))
    assert footprint_radii(rectangle(1.0, 1.0) + [2.0, 0.0])[0] == 0.0  # reference point outside


def test_footprint_cells_rotate_with_heading():
    along_x = footprint_cells(ROBOT, 0.0, 0.1)
    along_y = footprint_cells(ROBOT, math.pi / 2, 0.1)
    assert np.ptp(along_x[:, 1]) == 8 and np.ptp(along_x[:, 0]) == 2
    assert np.ptp(along_y[:, 0]) == 8 and np.ptp(along_y[:, 1]) == 2


def test_cspace_layer_is_the_footprint_dilation():
    occ = np.zeros((30, 30), bool)
    occ[15, 15] = True
    layers = cspace_layers(occ, ROBOT, 0.1, 8)
    for k in (0, 2, 3):
        expected = np.zeros_like(occ)
        for row in range(30):
            for col in range(30):
                expected[row, col] = footprint_collides(occ, ROBOT, 0.1, row, col, 2 * math.pi * k / 8)
        assert np.array_equal(layers[k], expected)


@pytest.mark.parametrize(
    "name, status, stage",
    [
        ("easy", R.SOLVED, "BAA"),
        ("medium", R.SOLVED, "full"),
        ("hard", R.SOLVED, "full"),
        ("impossible", R.NO_PATH_PROVEN, "ECA"),
    ],
)
def test_mspp_table1_stages(name, status, stage):
    grid, prob = SCENES[name]
    result = MultiStagePlanner(prob["footprint"]).plan(grid, prob["start"], prob["goal"])
    assert result.status == status, result.message
    assert result.stats.deciding_stage == stage
    assert [s.name for s in result.stats.stages][-1] == stage
    assert {"eca", "baa"} <= set(result.layers) or stage == "ECA"
    if status == R.SOLVED:
        assert_valid_path(grid, prob["footprint"], result.path, prob["start"], prob["goal"])
    else:
        assert "enclosed" in result.message and len(result.path) == 0


@pytest.mark.parametrize("name", ["easy", "medium", "hard", "impossible"])
def test_full_se2_agrees_with_mspp_on_solvability(name):
    grid, prob = SCENES[name]
    full = SE2AStarPlanner(prob["footprint"]).plan(grid, prob["start"], prob["goal"])
    assert full.success == (name != "impossible")
    assert full.stats.collision_checks > 0 and full.stats.expansions > 0
    if full.success:
        assert_valid_path(grid, prob["footprint"], full.path, prob["start"], prob["goal"])
    else:
        assert full.status == R.NO_PATH


@pytest.mark.parametrize("name", ["medium", "hard", "house"])
def test_mspp_local_paths_are_valid_and_local(name):
    grid, prob = SCENES[name]
    result = LocalMultiStagePlanner(prob["footprint"]).plan(grid, prob["start"], prob["goal"])
    assert result.success, result.message
    assert result.stats.deciding_stage == "local"
    assert len(result.layers["windows"]) >= 1
    assert_valid_path(grid, prob["footprint"], result.path, prob["start"], prob["goal"])
    full = SE2AStarPlanner(prob["footprint"]).plan(grid, prob["start"], prob["goal"])
    assert result.stats.expansions < full.stats.expansions or name == "medium"


def test_se2_finds_the_optimal_heading_change_in_open_space():
    grid = OccupancyGrid(np.zeros((20, 20), bool), 0.1)
    planner = SE2AStarPlanner(ROBOT, headings=16)
    result = planner.plan(grid, (1.0, 1.0, 0.0), (1.0, 1.0, math.pi / 2))
    # four quarter-turn steps in place, nothing else
    assert result.success and len(result.path) == 5
    assert result.stats.cost == pytest.approx(4 * planner.rotation_weight * 2 * math.pi / 16)


def test_se2_must_turn_to_pass_a_slot():
    occ = np.zeros((30, 30), bool)
    occ[15, :] = True
    occ[15, 14:17] = False  # a 0.3 m slot in a wall along x
    grid = OccupancyGrid(occ, 0.1)
    robot = rectangle(0.6, 0.2)
    result = SE2AStarPlanner(robot, headings=16).plan(grid, (1.55, 0.55, 0.0), (1.55, 2.55, 0.0))
    assert result.success
    assert_valid_path(grid, robot, result.path, (1.55, 0.55), (1.55, 2.55))
    crossing = [theta for x, y, theta in result.path if abs(y - 1.55) < 1e-9]
    assert crossing and all(abs(math.sin(t)) > 0.7 for t in crossing)  # not along the wall


@pytest.mark.parametrize("planner_id", registry.planner_ids())
def test_bad_requests_get_status_not_exceptions(planner_id):
    grid = table1("easy")
    cases = {
        R.INVALID_REQUEST: ((float("nan"), 2.0, 0.0), (5.0, 2.0, 0.0)),
        R.GOAL_OUTSIDE_MAP: ((1.0, 2.0, 0.0), (50.0, 2.0, 0.0)),
        R.START_OUTSIDE_MAP: ((-1.0, 2.0, 0.0), (5.0, 2.0, 0.0)),
        R.START_OCCUPIED: ((3.0, 0.5, 0.0), (5.0, 2.0, 0.0)),
        R.GOAL_OCCUPIED: ((1.0, 2.0, 0.0), (0.05, 0.05, 0.0)),
    }
    for status, (start, goal) in cases.items():
        result = registry.plan(planner_id, grid, start, goal, ROBOT)
        assert result.status == status, (status, result.message)
        assert result.message and len(result.path) == 0


OPEN = OccupancyGrid(np.pad(np.zeros((38, 58), bool), 1, constant_values=True), 0.1)
SQUAT = rectangle(0.4, 0.36)  # biped_wall cannot walk a long thin gait (0.9 x 0.3) even in an open room
_closed = OPEN.occupied.copy()
_closed[:, 29:31] = True
CLOSED = OccupancyGrid(_closed, 0.1)  # a wall right across the room: no robot gets through


@pytest.mark.parametrize("planner_id", registry.planner_ids())
def test_every_planner_solves_an_open_room(planner_id):
    result = registry.plan(planner_id, OPEN, (1.0, 2.0, 0.0), (5.0, 2.0, 0.0), SQUAT, time_limit=60.0)
    assert result.success, result.message
    assert result.path[0, :2] == pytest.approx((1.0, 2.0), abs=0.051)
    assert result.path[-1, :2] == pytest.approx((5.0, 2.0), abs=0.051)
    assert result.stats.planning_time > 0 and result.stats.to_dict()["deciding_stage"] == result.stats.deciding_stage


@pytest.mark.parametrize("planner_id", registry.planner_ids())
def test_every_planner_reports_no_path_and_only_provers_prove_it(planner_id):
    result = registry.plan(planner_id, CLOSED, (1.0, 2.0, 0.0), (5.0, 2.0, 0.0), SQUAT, time_limit=60.0)
    proven = registry.spec(planner_id).has(registry.PROVES_NO_PATH)
    assert result.status == (R.NO_PATH_PROVEN if proven else R.NO_PATH), result.message
    assert len(result.path) == 0 and result.message


@pytest.mark.parametrize("planner_id", registry.planner_ids())
@pytest.mark.parametrize("time_limit", [0.0, -1.0, float("nan")])
def test_every_planner_refuses_a_bad_time_limit(planner_id, time_limit):
    result = registry.plan(planner_id, OPEN, (1.0, 2.0, 0.0), (5.0, 2.0, 0.0), ROBOT, time_limit=time_limit)
    assert result.status == R.INVALID_REQUEST and "time limit" in result.message


@pytest.mark.parametrize("planner_id", registry.planner_ids())
def test_every_planner_declares_documented_parameters_it_accepts(planner_id):
    spec = registry.spec(planner_id)
    for name, param in spec.params.items():
        assert param.description, name
        assert param.check(param.default) == param.default
    registry.make_planner(planner_id, ROBOT, **{name: p.default for name, p in spec.params.items()})
    with pytest.raises(InvalidRequest, match="no parameter 'bogus'"):
        registry.make_planner(planner_id, ROBOT, bogus=1)


def test_registry_rejects_unknown_planner_and_bad_params():
    with pytest.raises(InvalidPlanner, match="unknown base planner 'rrt'"):
        registry.plan("rrt", table1("easy"), (1, 2, 0), (5, 2, 0), ROBOT)
    with pytest.raises(InvalidRequest, match="headings"):
        registry.plan("se2", table1("easy"), (1, 2, 0), (5, 2, 0), ROBOT, headings=0)
    with pytest.raises(InvalidRequest, match="footprint"):
        registry.plan("mspp", table1("easy"), (1, 2, 0), (5, 2, 0), [[0, 0], [1, 1]])
    with pytest.raises(InvalidRequest, match="no parameter 'headings'"):  # tunnel has no headings to ignore
        registry.plan("tunnel", table1("easy"), (1, 2, 0), (5, 2, 0), ROBOT, headings=32)


def test_astar_planner_uses_circumradius():
    grid, prob = SCENES["medium"]
    result = registry.plan("astar", grid, prob["start"], prob["goal"], prob["footprint"])
    assert result.status == R.NO_PATH  # the 0.6 m passage is narrower than 2 R_max
    easy = registry.plan("astar", SCENES["easy"][0], prob["start"], prob["goal"], prob["footprint"])
    assert easy.success
    assert_valid_path(SCENES["easy"][0], prob["footprint"], easy.path, prob["start"], prob["goal"])


def test_timeout_is_reported():
    grid, prob = SCENES["house"]
    result = SE2AStarPlanner(prob["footprint"]).plan(grid, prob["start"], prob["goal"], time_limit=1e-4)
    assert result.status == R.TIMED_OUT


def test_cli_writes_json_and_png(tmp_path):

    out, png = tmp_path / "o.json", tmp_path / "o.png"
    code = main(
        [
            "--map",
            str(config_path("maps", "paper002_medium.yaml")),
            "--planner",
            "mspp",
            "--start",
            "1",
            "2",
            "0",
            "--goal",
            "5",
            "2",
            "0",
            "--footprint",
            "0.45,0.15 -0.45,0.15 -0.45,-0.15 0.45,-0.15",
            "--json",
            str(out),
            "--png",
            str(png),
        ]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert set(data) == {"success", "status", "message", "path", "stats", "clearance"}
    assert 0.0 < data["clearance"]["min_m"] <= data["clearance"]["mean_m"]
    assert data["success"] and data["status"] == "solved" and data["stats"]["deciding_stage"] == "full"
    assert len(data["path"][0]) == 3 and png.stat().st_size > 1000
    code = main(
        [
            "--map",
            str(config_path("maps", "paper002_impossible.yaml")),
            "--start",
            "1",
            "2",
            "0",
            "--goal",
            "5",
            "2",
            "0",
            "--json",
            str(out),
        ]
    )
    assert code == 1 and json.loads(out.read_text())["status"] == "no_path_proven"
    assert main(["--map", str(tmp_path / "missing.yaml"), "--start", "1", "2", "0", "--goal", "5", "2", "0"]) == 2


def test_shipped_maps_match_the_scene_builder():
    for name, (grid, _) in SCENES.items():
        loaded = OccupancyGrid.from_yaml(config_path("maps", f"paper002_{name}.yaml"))
        assert loaded.resolution == grid.resolution and loaded.origin == grid.origin
        assert np.array_equal(loaded.occupied, grid.occupied), name


def _z_slot_scene() -> OccupancyGrid:
    """A 1 m thick wall with a short Z-shaped 0.4 m slot (ECA-open, too tight to turn in) and a 0.6 m
    opening above (passable at heading 0, far longer)."""
    occ = np.zeros((40, 60), bool)
    occ[0] = occ[-1] = occ[:, 0] = occ[:, -1] = True
    ys, xs = (np.arange(40) + 0.5) * 0.1, (np.arange(60) + 0.5) * 0.1

    def box(x0, y0, x1, y1):
        return np.ix_((ys >= y0) & (ys <= y1), (xs >= x0) & (xs <= x1))

    occ[box(2.5, 0.0, 3.5, 3.3)] = True
    for x0, y0, x1, y1 in ((2.5, 0.8, 3.2, 1.2), (2.8, 0.8, 3.2, 1.8), (2.8, 1.4, 3.5, 1.8)):
        occ[box(x0, y0, x1, y1)] = False
    return OccupancyGrid(occ, 0.1)


def test_mspp_local_falls_back_to_full_search_when_windows_fail():
    grid = _z_slot_scene()
    prob = {"footprint": ROBOT, "start": (1.0, 1.0, 0.0), "goal": (5.0, 1.6, 0.0)}
    # no margin: the windows stay around the slot the guide path takes, where the robot cannot turn
    planner = LocalMultiStagePlanner(prob["footprint"], local_margin=0.0)
    result = planner.plan(grid, prob["start"], prob["goal"])
    assert result.success and result.stats.deciding_stage == "full"
    assert result.path[:, 1].max() > 3.3  # through the opening above the wall
    assert [s.name for s in result.stats.stages] == ["ECA", "BAA", "local", "full"]
    local = result.stats.stages[2]
    assert local.fallback and local.windows and not any(w.found for w in local.windows)
    assert_valid_path(grid, prob["footprint"], result.path, prob["start"], prob["goal"])


def test_se2_heap_grows_from_a_tiny_capacity():
    grid, prob = SCENES["hard"]
    planner = SE2AStarPlanner(prob["footprint"])
    layers = cspace_layers(grid.occupied, prob["footprint"], grid.resolution, 32)
    start, goal = grid.world_to_cell(*prob["start"][:2]), grid.world_to_cell(*prob["goal"][:2])
    args = (layers, [(0, *start)], goal, 0, planner.rot_cost_cells(grid.resolution))
    small, big = search_layers(*args, initial_capacity=4), search_layers(*args)
    assert small.found and big.found
    assert small.cost == pytest.approx(big.cost) and np.array_equal(small.states, big.states)


def test_stamping_and_dilation_give_the_same_cspace():
    rng = np.random.default_rng(3)
    occ = rng.random((23, 31)) < 0.08
    poly = np.array([[0.3, 0.0], [-0.2, 0.25], [-0.25, -0.1], [0.1, -0.2]])  # asymmetric
    offsets = heading_offsets(poly, 0.05, 12)
    assert np.array_equal(cspace_layers(occ, poly, 0.05, 12), np.stack([dilate(occ, o) for o in offsets]))
