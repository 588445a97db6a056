"""Replay recorded rosbag2 bags through the real reactive_node, and run it closed loop with the simulator.

Bags: fresh ones recorded by ``scripts/record_reactive_bags.py`` at session
start (their ``/cmd_vel`` is the core controller's answer to the same
messages, so the node must reproduce it exactly) and the committed ones under
``test/data/`` (replayed twice for determinism). Every replay gets its own
node process in its own namespace, so each starts from a fresh controller.
The node runs on sim time: the replay publishes ``/clock`` (remapped into the
namespace) from the bag's receive times, as ``ros2 bag play --clock`` would.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import yaml
from reactive_helpers import NODE_MODULE, ReactiveClient, reactive_params_file, shipped_params

from maru_planner.bag import read_messages, summarize
from maru_planner.paths import config_path
from maru_planner.sim import World

pytestmark = pytest.mark.ros

REPO_ROOT = Path(__file__).resolve().parents[2]
DATA = REPO_ROOT / "test" / "data"
SCENARIOS = ["single_static", "goal_behind_obstacle", "walking_person", "multiple_static", "irregular_scattered"]
_namespaces = itertools.count()


def _load_recorder():
    spec = importlib.util.spec_from_file_location("record_reactive_bags", REPO_ROOT / "scripts/record_reactive_bags.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def recorded_bags(tmp_path_factory):
    """The default scenario bags recorded now with the current core (a second or two)."""
    recorder = _load_recorder()
    out = tmp_path_factory.mktemp("reactive_bags")
    bags = {}
    for name, skip, duration, storage in recorder.DEFAULT_BAGS:
        bags[name] = out / f"reactive_{name}"
        recorder.record_world(
            config_path("worlds", f"{name}.yaml"), bags[name], skip=skip, duration=duration, storage=storage
        )
    return bags


@dataclass
class Replay:
    """What the node published for a bag, next to what the bag holds."""

    twists: list = field(default_factory=list)  # (v, w) per published Twist
    reference: list = field(default_factory=list)  # (v, w) recorded by the core
    scans: list = field(default_factory=list)  # LaserScan messages fed, valid ones only
    strips: list = field(default_factory=list)
    arm: list = field(default_factory=list)


def _start_node(node_process, tmp_path: Path):
    ns = f"/replay{next(_namespaces)}"
    params = reactive_params_file(
        tmp_path, scan_reliability="reliable", status_period=1.0, use_sim_time=True, scan_timeout=600.0
    )  # lock-step on a loaded machine: no watchdog stop between steps
    args = [
        "--ros-args",
        "-r",
        f"__ns:={ns}",
        "-r",
        f"/clock:={ns}/clock",
        "--params-file",
        str(config_path("reactive.yaml")),
        "--params-file",
        str(params),
    ]
    return ns, node_process(NODE_MODULE, args)


def replay_bag(bag: Path, node_process, spinning_factory, tmp_path: Path, inject_every: int = 0) -> Replay:
    """Feed a bag to a fresh node lock-step; optionally a malformed scan before every ``inject_every``-th scan."""
    from reactive_helpers import malformed_scans

    from maru_planner.ros import reactive_conversions as conv

    ns, process = _start_node(node_process, tmp_path)
    spinning = spinning_factory(f"replay_client_{ns[1:]}")
    client = ReactiveClient(spinning, namespace=ns, process=process)
    client.wait_connected()
    result = Replay()
    odom = None
    bad = itertools.cycle(range(3))
    for record in read_messages(bag):
        msg = conv.decode_bag_record(record.msgtype, record.rawdata) if record.topic != "/tf" else None
        if record.topic == "/goal_pose":
            client.send_and_confirm(client.goal_pub, msg, process, "goal (")
        elif record.topic == "/plan":
            client.send_and_confirm(client.plan_pub, msg, process, "initial path with")
        elif record.topic == "/odom":
            odom = msg
        elif record.topic == "/cmd_vel":
            result.reference.append((msg.linear.x, msg.angular.z))
        elif record.topic == "/scan":
            if inject_every and len(result.scans) % inject_every == 0:
                client.scan_pub.publish(malformed_scans(conv.stamp_to_s(msg.header.stamp))[next(bad)])
            client.step(odom, msg, clock_ns=record.timestamp_ns)
            result.scans.append(msg)
    assert spinning.wait_for(
        lambda: len(client.strips) >= len(result.scans) and len(client.arm) >= len(result.scans), timeout=60
    )
    answers = [client.stamped[conv.stamp_to_ns(scan.header.stamp)] for scan in result.scans]
    assert client.plain_twists_end_with(answers), "cmd_vel must carry the same commands as cmd_vel_stamped"
    result.twists = [(t.linear.x, t.angular.z) for t in answers]
    result.strips, result.arm = list(client.strips), list(client.arm)
    assert process.alive(), process.log()[-2000:]
    return result


@pytest.fixture(scope="module")
def spinning_factory(rclpy_session):
    from conftest import SpinningNode

    made = []

    def make(name: str):
        made.append(SpinningNode(name))
        return made[-1]

    yield make
    for spinning in made:
        spinning.destroy()


@pytest.fixture(scope="module")
def replays(recorded_bags, node_process, spinning_factory, tmp_path_factory):
    """Replay results, computed once per (bag, variant)."""
    cache: dict = {}
    tmp = tmp_path_factory.mktemp("replay_params")

    def get(bag: Path, variant: str = "clean", inject_every: int = 0) -> Replay:
        key = (str(bag), variant)
        if key not in cache:
            cache[key] = replay_bag(bag, node_process, spinning_factory, tmp, inject_every=inject_every)
        return cache[key]

    return get


# ---------------------------------------------------------------- replays
@pytest.mark.parametrize("scenario", SCENARIOS)
def test_replayed_commands_equal_the_core_and_stay_within_limits(scenario, recorded_bags, replays):
    result = replays(recorded_bags[scenario])
    limits = shipped_params()
    assert len(result.twists) == len(result.scans) == len(result.reference) >= 20
    v = np.array([t[0] for t in result.twists])
    w = np.array([t[1] for t in result.twists])
    assert np.all(np.abs(v) <= limits["max_linear"] + 1e-12), f"|v| up to {np.abs(v).max()}"
    assert np.all(np.abs(w) <= limits["max_angular"] + 1e-12), f"|w| up to {np.abs(w).max()}"
    np.testing.assert_allclose(result.twists, result.reference, rtol=0, atol=1e-12)
    stamps = [msg.header.stamp for msg in result.scans]
    assert [s.header.stamp for s in result.strips] == stamps, "one strip per scan, stamped with the scan's time"


def _nearest_front_obstacle(scan_msg, laser_pose, window):
    """(distance from base centre, bearing) of the nearest in-window scan point, in base_link."""
    from maru_planner.reactive import scan_to_points
    from maru_planner.ros import reactive_conversions as conv

    points = scan_to_points(conv.scan_from_msg(scan_msg), laser_pose, window)
    if len(points) == 0:
        return math.inf, 0.0
    i = int(np.argmin(np.hypot(points[:, 0], points[:, 1])))
    return float(np.hypot(*points[i])), math.atan2(points[i, 1], points[i, 0])


def _goal_seeking_w(pose, goal, params) -> float:
    """The turn rate the base would get heading straight for the goal (no obstacles), as the core computes it."""
    error = math.atan2(goal[1] - pose[1], goal[0] - pose[0]) - pose[2]
    error = math.atan2(math.sin(error), math.cos(error))
    return max(-params.max_angular, min(params.max_angular, params.k_angular * error))


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_commands_turn_away_from_obstacles_close_ahead(scenario, recorded_bags, replays):
    """Whenever the nearest scan point is within d_0 + 0.5 m and off to one side ahead (5..45 deg), the
    commanded turn rate is further from that side than heading straight for the goal would be:
    (w - w_goal) has the opposite sign to the point's bearing."""
    from maru_planner.ros import reactive_conversions as conv
    from maru_planner.ros.reactive_node import strip_params_from_config

    result = replays(recorded_bags[scenario])
    params = strip_params_from_config(config_path("reactive.yaml"))
    records = [r for r in read_messages(recorded_bags[scenario], topics=["/goal_pose", "/odom"])]
    goal = conv.pose_from_pose_stamped(conv.decode_bag_record(records[0].msgtype, records[0].rawdata))
    poses = [conv.pose_from_odom(conv.decode_bag_record(r.msgtype, r.rawdata)) for r in records[1:]]
    checked = 0
    for scan, pose, (_v, w) in zip(result.scans, poses, result.twists, strict=True):
        distance, bearing = _nearest_front_obstacle(scan, params.laser_pose, params.beam_window)
        if distance < params.d0 + 0.5 and math.radians(5) < abs(bearing) < math.radians(45):
            checked += 1
            w_goal = _goal_seeking_w(pose, goal, params)
            assert (w - w_goal) * bearing < 0.0, (
                f"obstacle at {distance:.2f} m, bearing {math.degrees(bearing):.0f} deg: w = {w:.3f}, "
                f"towards the goal {w_goal:.3f}"
            )
    assert checked >= 3, f"only {checked} scans with an obstacle close ahead: the bag does not test avoidance"


def test_malformed_scans_injected_into_a_replay_change_no_command(recorded_bags, replays):
    clean = replays(recorded_bags["single_static"])
    noisy = replays(recorded_bags["single_static"], variant="malformed", inject_every=4)
    assert noisy.twists == clean.twists, "malformed scans must be dropped without touching the controller"


def test_same_committed_bag_gives_the_same_commands(replays):
    bag = DATA / "reactive_goal_behind_obstacle"
    first = replays(bag, variant="run1")
    second = replays(bag, variant="run2")
    assert len(first.twists) >= 40
    assert first.twists == second.twists
    assert [list(a.points[0].positions) for a in first.arm] == [list(a.points[0].positions) for a in second.arm]
    assert [[(p.pose.position.x, p.pose.position.y) for p in s.poses] for s in first.strips] == [
        [(p.pose.position.x, p.pose.position.y) for p in s.poses] for s in second.strips
    ]


def test_committed_bags_hold_the_recorded_topics_and_stay_small():
    recorder = _load_recorder()
    for name, _skip, duration, storage in recorder.DEFAULT_BAGS:
        bag = DATA / f"reactive_{name}"
        summary = summarize(bag)
        assert summary.storage == storage
        assert summary.topics == recorder.TOPICS
        ticks = summary.counts["/scan"]
        assert summary.counts == {
            "/goal_pose": 1,
            "/plan": 1,
            "/tf": ticks,
            "/odom": ticks,
            "/scan": ticks,
            "/cmd_vel": ticks,
        }
        rate = World.from_yaml(config_path("worlds", f"{name}.yaml")).robot.laser.rate
        assert ticks == pytest.approx(duration * rate, abs=1), "recorded at the world's laser rate"
        size = sum(f.stat().st_size for f in bag.iterdir())
        assert size < 400_000, f"{bag} is {size} bytes"
        meta = yaml.safe_load((bag / "metadata.yaml").read_text())
        assert meta["rosbag2_bagfile_information"]["storage_identifier"] == storage


# ---------------------------------------------------------------- closed loop over DDS
CLOSED_LOOP_WORLD = {
    "name": "closed_loop_post",
    "obstacles": [{"type": "circle", "center": [1.8, 0.1], "radius": 0.3}],
    "robot": {"start": [0.0, 0.0, 0.0], "goal": [3.6, 0.0, 0.0]},
    "goal_tolerance": 0.3,
    "max_time": 20.0,
}


def test_closed_loop_simulator_and_node_reach_the_goal_without_collision(node_process, spinning_factory, tmp_path):
    """The simulator (here) publishes odom + scan, steps on each /cmd_vel; the node runs as its own process."""
    from maru_planner.ros import reactive_conversions as conv
    from maru_planner.sim import Simulator, World

    world = World.from_dict(CLOSED_LOOP_WORLD)
    sim = Simulator(world, seed=3)
    dt, base = 0.1, 100.0
    ns, process = _start_node(node_process, tmp_path)
    client = ReactiveClient(spinning_factory(f"closed_loop_{ns[1:]}"), namespace=ns, process=process)
    client.wait_connected()
    goal = tuple(world.robot.goal)
    client.send_and_confirm(client.goal_pub, conv.pose_stamped_msg(goal, "odom", base), process, "goal (")
    min_clearance, v, w = sim.clearance(), 0.0, 0.0
    while sim.time < world.max_time and sim.goal_distance() > world.goal_tolerance:
        stamp = base + sim.time
        scan = sim.scan()
        scan.stamp = stamp
        twist = client.step(
            conv.odom_msg(sim.robot_pose, v, w, stamp, "odom", "base_link"),
            conv.scan_msg(scan, "laser_link", scan_time=dt),
        )
        v, w = twist.linear.x, twist.angular.z
        assert not sim.step(v, w, dt), f"collision at {sim.robot_pose} (t = {sim.time:.1f} s)"
        min_clearance = min(min_clearance, sim.clearance())
    assert sim.goal_distance() <= world.goal_tolerance, f"stopped at {sim.robot_pose} after {sim.time:.1f} s"
    assert min_clearance > 0.0
    assert client.spinning.wait_for(lambda: len(client.markers) > 0, 60), "markers go out while someone listens"
    assert [m.ns for m in client.markers[-1].markers][:3] == ["strip", "vias", "obstacles"]
    assert process.alive()
