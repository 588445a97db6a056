"""Simulator: ray caster against analytic distances, maps, movers, collisions, world-file errors, CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml

from maru_planner.paths import config_path
from maru_planner.sim import Simulator, World, WorldError
from maru_planner.sim.geometry import rays_vs_circles, rays_vs_segments

ROBOT = {"start": [0, 0, 0], "goal": [5, 0, 0], "laser": {"x": 0.0, "noise": 0.0}}


def world(obstacles=(), **extra) -> World:
    return World.from_dict({"obstacles": list(obstacles), "robot": dict(ROBOT), **extra})


def test_ray_vs_circle_analytic():
    dirs = np.array([[1.0, 0.0], [0.0, 1.0], [math.cos(0.1), math.sin(0.1)]])
    r = rays_vs_circles(np.zeros(2), dirs, np.array([[3.0, 0.0, 0.5]]), 10.0)
    assert r[0] == pytest.approx(2.5)
    assert np.isinf(r[1])
    # ray at angle a hits where |t u - c| = R: t = c cos a - sqrt(R^2 - c^2 sin^2 a)
    a = 0.1
    assert r[2] == pytest.approx(3 * math.cos(a) - math.sqrt(0.25 - 9 * math.sin(a) ** 2))


def test_ray_vs_segment_analytic():
    dirs = np.array([[1.0, 0.0], [math.cos(0.4), math.sin(0.4)], [-1.0, 0.0], [math.cos(0.5), math.sin(0.5)]])
    r = rays_vs_segments(np.zeros(2), dirs, np.array([[2.0, -1.0, 2.0, 1.0]]))
    assert r[0] == pytest.approx(2.0)
    assert r[1] == pytest.approx(2.0 / math.cos(0.4))
    assert np.isinf(r[2]) and np.isinf(r[3])  # behind, and past the end (2 tan 0.5 > 1)


def test_lms200_scan_geometry_and_box_distances():
    w = world([{"type": "box", "center": [3.0, 0.0], "size": [1.0, 8.0]}])
    scan = Simulator(w).scan()
    assert scan.ranges.size == 361
    assert scan.angle_min == pytest.approx(-math.pi / 2) and scan.angle_increment == pytest.approx(math.radians(0.5))
    angles = scan.angles
    front = np.abs(angles) < math.atan(4.0 / 2.5)
    assert scan.ranges[front] == pytest.approx(2.5 / np.cos(angles[front]))  # the face x = 2.5
    assert np.all(np.isinf(scan.ranges[np.abs(angles) > math.atan(4.0 / 2.5) + 0.01]))  # pass the box's ends


def test_range_max_gives_inf_and_noise_is_seeded():
    w = world([{"type": "circle", "center": [12.0, 0.0], "radius": 0.5}])
    assert np.all(np.isinf(Simulator(w).scan().ranges))
    w2 = world([{"type": "circle", "center": [3.0, 0.0], "radius": 0.5}])
    a = Simulator(w2, seed=3, noise=0.02).scan().ranges
    b = Simulator(w2, seed=3, noise=0.02).scan().ranges
    c = Simulator(w2, seed=4, noise=0.02).scan().ranges
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert abs(a[180] - 2.5) < 0.1


def test_map_server_map_is_ray_cast_and_collides(tmp_path):
    from PIL import Image

    pixels = np.full((40, 40), 254, dtype=np.uint8)  # 0.1 m cells, 4 x 4 m, origin (-1, -2)
    pixels[:, 30:] = 0  # occupied for x >= 2.0
    Image.fromarray(pixels).save(tmp_path / "room.pgm")
    (tmp_path / "room.yaml").write_text(
        yaml.safe_dump(
            {
                "image": "room.pgm",
                "resolution": 0.1,
                "origin": [-1.0, -2.0, 0.0],
                "negate": 0,
                "occupied_thresh": 0.65,
                "free_thresh": 0.196,
            }
        )
    )
    w = World.from_dict({"map": "room.yaml", "robot": dict(ROBOT)}, base_dir=tmp_path)
    sim = Simulator(w)
    assert sim.scan().ranges[180] == pytest.approx(2.0, abs=0.06)
    assert sim.clearance() == pytest.approx(2.0 - 0.3, abs=0.11)
    sim.robot_pose = (1.75, 0.0, 0.0)
    assert sim.clearance() < 0


def test_clearance_and_collision_for_circle_robot_and_footprint():
    w = world([{"type": "circle", "center": [1.0, 0.0], "radius": 0.2}])
    sim = Simulator(w)
    assert sim.clearance() == pytest.approx(1.0 - 0.2 - 0.3)
    assert not sim.step(0.5, 0.0, 0.5)
    hit = False
    for _ in range(10):
        hit = sim.step(0.5, 0.0, 0.2) or hit
    assert hit and sim.collided
    assert sim.clearance() >= 0.0  # bumper stop: the overlapping step is not taken
    box = World.from_dict(
        {
            "obstacles": [{"type": "circle", "center": [1.0, 0.0], "radius": 0.2}],
            "robot": {**ROBOT, "footprint": [[0.21, 0.165], [-0.21, 0.165], [-0.21, -0.165], [0.21, -0.165]]},
        }
    )
    assert Simulator(box).clearance() == pytest.approx(1.0 - 0.2 - 0.21)


def test_movers_follow_waypoints_at_speed():
    w = world(movers=[{"radius": 0.25, "speed": 1.2, "waypoints": [[3, -4], [3, 4]], "start_time": 1.0}])
    m = w.movers[0]
    assert m.position(0.5) == pytest.approx([3, -4])
    assert m.position(1.0 + 2.5) == pytest.approx([3, -1])
    assert m.position(100.0) == pytest.approx([3, 4])
    assert w.circles_at(1.0 + 10 / 3)[-1] == pytest.approx([3, 0, 0.25])
    loop = world(movers=[{"speed": 1.0, "waypoints": [[0, 0], [2, 0]], "mode": "pingpong"}]).movers[0]
    assert loop.position(3.0) == pytest.approx([1, 0])


@pytest.mark.parametrize(
    "data, match",
    [
        ({"obstacles": []}, "missing field 'robot'"),
        ({"robot": {"start": [0, 0, 0]}}, "missing field 'goal'"),
        ({"robot": {"start": [0, 0], "goal": [1, 0, 0]}}, "robot.start"),
        ({"robot": ROBOT, "obstacles": [{"type": "cone"}]}, "unknown obstacle type"),
        ({"robot": ROBOT, "obstacles": [{"type": "circle", "center": [0, 0], "radius": -1}]}, "radius"),
        ({"robot": ROBOT, "obstacles": [{"type": "polygon", "points": [[0, 0], [1, 1]]}]}, "at least 3"),
        ({"robot": ROBOT, "movers": [{"waypoints": [[0, 0]]}]}, "2 waypoints"),
        ({"robot": ROBOT, "movers": [{"waypoints": [[0, 0], [1, 0]], "mode": "bounce"}]}, "mode"),
        ({"robot": {**ROBOT, "laser": {"fov": 90}}}, "laser"),
        ({"robot": ROBOT, "colour": "red"}, "unknown field"),
        ({"robot": ROBOT, "map": "missing.yaml"}, "cannot read"),
        ({"robot": ROBOT, "obstacles": 5}, "obstacles: expected a list"),
        ({"robot": {**ROBOT, "laser": {"range_min": 5.0, "range_max": 1.0}}}, "range_min < range_max"),
        ({"robot": {**ROBOT, "laser": {"rate": 1e6}}}, "robot.laser.rate"),
        ({"robot": ROBOT, "movers": [{"waypoints": [[0, 0], [1, 0]], "start_time": "soon"}]}, "start_time"),
        ([1, 2], "mapping"),
    ],
)
def test_world_errors_name_the_field(data, match, tmp_path):
    with pytest.raises(WorldError, match=match):
        World.from_dict(data, base_dir=tmp_path)


def test_world_file_yaml_errors(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("robot: [unclosed")
    with pytest.raises(WorldError, match="invalid YAML"):
        World.from_yaml(bad)
    with pytest.raises(WorldError, match="cannot read"):
        World.from_yaml(tmp_path / "none.yaml")


@pytest.mark.parametrize(
    "name", ["single_static", "goal_behind_obstacle", "multiple_static", "irregular_scattered", "walking_person"]
)
def test_paper_worlds_load_with_free_start_and_goal(name):
    w = World.from_yaml(config_path("worlds", f"{name}.yaml"))
    sim = Simulator(w)
    assert sim.clearance() > 0.3
    sim.robot_pose = tuple(w.robot.goal)
    assert sim.clearance() > 0.3


def test_cli_writes_json_and_png(tmp_path):
    from maru_planner.sim.cli import main

    w = tmp_path / "w.yaml"
    w.write_text(
        yaml.safe_dump(
            {
                "obstacles": [{"type": "circle", "center": [1.5, 0.4], "radius": 0.2}],
                "robot": {"start": [0, 0, 0], "goal": [3, 0, 0]},
                "max_time": 30,
            }
        )
    )
    out, png = tmp_path / "o.json", tmp_path / "o.png"
    assert (
        main(
            [
                "--world",
                str(w),
                "--strip",
                "modified",
                "--seed",
                "1",
                "--json",
                str(out),
                "--png",
                str(png),
                "--quiet",
                "--no-arm",
            ]
        )
        == 0
    )
    data = json.loads(out.read_text())
    for key in ("success", "outcome", "collisions", "time_to_goal", "path_length", "min_clearance", "update_ms"):
        assert key in data
    assert data["outcome"] == "goal" and data["success"] is True and data["collisions"] == 0
    assert set(data["update_ms"]) == {"median", "p99"}
    assert png.stat().st_size > 1000
    assert main(["--world", str(tmp_path / "nope.yaml"), "--quiet"]) == 2


def test_fan_caster_matches_brute_force_caster():
    from maru_planner.sim.geometry import fan_vs_circles

    rng = np.random.default_rng(5)
    circles = np.column_stack([rng.uniform(-6, 6, 300), rng.uniform(-6, 6, 300), rng.uniform(0.05, 0.4, 300)])
    circles = circles[np.hypot(circles[:, 0], circles[:, 1]) > circles[:, 2] + 0.01]
    angle0, inc, count = -2.356, math.radians(0.375), 721
    a = angle0 + inc * np.arange(count)
    dirs = np.stack([np.cos(a), np.sin(a)], axis=1)
    brute = rays_vs_circles(np.zeros(2), dirs, circles, 10.0)
    fan = fan_vs_circles(np.zeros(2), angle0, inc, count, circles, 10.0)
    assert np.allclose(np.where(np.isinf(brute), -1, brute), np.where(np.isinf(fan), -1, fan))
