"""base_planner_node end to end: a subprocess on loopback DDS, real rclpy clients, bad input included."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest
from conftest import BaseNodeClient

from maru_planner.base.scenes import table1
from maru_planner.paths import config_path
from maru_planner.ros.reactive_conversions import pose_stamped_msg

pytestmark = pytest.mark.ros

NODE_MODULE = "maru_planner.ros.base_planner_node"
START, GOAL = (1.0, 2.0, 0.0), (5.0, 2.0, 0.0)
TEST_DIR = Path(__file__).resolve().parents[1]
TOY_PLANNER = "toy_straight"  # test/toy_base_planner.py


@pytest.fixture(scope="module")
def node(node_process):
    proc = node_process(NODE_MODULE, ["--ros-args", "--params-file", str(config_path("base_planner.yaml"))])
    return proc


class Client(BaseNodeClient):
    def __init__(self, spinning, proc, namespace: str = ""):
        from nav_msgs.msg import OccupancyGrid, Path
        from nav_msgs.srv import GetPlan

        super().__init__(spinning, proc, namespace)
        node = spinning.node
        self.get_plan_client = node.create_client(GetPlan, "/make_plan")
        self.paths, self.eca_maps = [], []
        node.create_subscription(Path, "/plan", self.paths.append, self.latched)
        node.create_subscription(OccupancyGrid, "/base_planner_node/eca_map", self.eca_maps.append, self.latched)

    def request(self, start=START, goal=GOAL, planner_id="", footprint=None, frame="map", time_limit=0.0):
        from geometry_msgs.msg import Point32

        from maru_planner_interfaces.srv import PlanBasePath

        req = PlanBasePath.Request()
        req.planner_id = planner_id
        req.footprint = [Point32(x=float(x), y=float(y)) for x, y in (footprint or [])]
        req.start, req.goal = pose_stamped_msg(start, frame, 0.0), pose_stamped_msg(goal, frame, 0.0)
        req.allowed_planning_time = time_limit
        return self.spinning.call(self.plan_client, req, timeout=60)


def map_msg(grid, *, width=None, height=None, data=None):
    from maru_planner.ros.base_conversions import grid_to_msg

    msg = grid_to_msg(grid, grid.occupied, None or _zero_stamp(), "map")
    if width is not None:
        msg.info.width = width
    if height is not None:
        msg.info.height = height
    if data is not None:
        msg.data = data
    return msg


def _zero_stamp():
    from builtin_interfaces.msg import Time

    return Time()


@pytest.fixture
def client(spinning_node, node):
    return Client(spinning_node, node)


def test_no_map_yet(client):
    from maru_planner_interfaces.srv import PlanBasePath

    response = client.request()
    assert response.error_code == PlanBasePath.Response.NO_MAP
    assert "no map" in response.error_msg


def test_plan_on_medium_map_through_both_services(client):
    from nav_msgs.srv import GetPlan

    from maru_planner_interfaces.srv import PlanBasePath

    client.publish_map(map_msg(table1("medium")), "map 60 x 40 cells")
    response = client.request(planner_id="mspp")
    assert response.error_code == PlanBasePath.Response.NONE, response.error_msg
    assert response.deciding_stage == "full" and response.expansions > 0 and response.collision_checks > 0
    poses = response.path.poses
    assert len(poses) > 10 and response.path.header.frame_id == "map"
    assert abs(poses[0].pose.position.x - 1.05) < 1e-9 and abs(poses[-1].pose.position.x - 5.05) < 1e-9
    stats = json.loads(response.stats_json)
    assert [s["name"] for s in stats["stages"]] == ["ECA", "BAA", "full"]
    assert client.spinning.wait_for(lambda: len(client.paths) >= 1)
    assert len(client.paths[-1].poses) == len(poses)
    # grown maps are published to subscribers
    assert client.spinning.wait_for(lambda: len(client.eca_maps) >= 1 or client.request().error_code != 0, 5)
    client.request()
    assert client.spinning.wait_for(lambda: len(client.eca_maps) >= 1)
    assert sum(v == 100 for v in client.eca_maps[-1].data) > sum(v == 100 for v in map_msg(table1("medium")).data)

    req = GetPlan.Request()
    req.start, req.goal = pose_stamped_msg(START, "map", 0.0), pose_stamped_msg(GOAL, "map", 0.0)
    plan = client.spinning.call(client.get_plan_client, req, timeout=60).plan
    assert len(plan.poses) == len(poses)
    req.goal = pose_stamped_msg((float("nan"), 2.0, 0.0), "map", 0.0)
    assert len(client.spinning.call(client.get_plan_client, req, timeout=60).plan.poses) == 0


@pytest.mark.parametrize("planner_id", ["astar", "se2", "mspp_local"])
def test_other_planners(client, planner_id):
    from maru_planner_interfaces.srv import PlanBasePath

    response = client.request(planner_id=planner_id)
    expected = PlanBasePath.Response.NO_VALID_PATH if planner_id == "astar" else PlanBasePath.Response.NONE
    assert response.error_code == expected, response.error_msg


def test_bad_requests_keep_the_node_serving(client):
    from maru_planner_interfaces.srv import PlanBasePath

    E = PlanBasePath.Response
    cases = [
        (dict(start=(float("nan"), 2.0, 0.0)), E.INVALID_REQUEST, "NaN"),
        (dict(goal=(40.0, 2.0, 0.0)), E.GOAL_OUTSIDE_MAP, "outside the map"),
        (dict(start=(-3.0, 2.0, 0.0)), E.START_OUTSIDE_MAP, "outside the map"),
        (dict(start=(3.0, 0.5, 0.0)), E.START_OCCUPIED, "collision"),
        (dict(goal=(3.0, 3.5, 0.0)), E.GOAL_OCCUPIED, "collision"),
        (dict(planner_id="rrt_star"), E.INVALID_PLANNER, "rrt_star"),
        (dict(footprint=[(0, 0), (1, 0)]), E.INVALID_REQUEST, "footprint"),
        (dict(frame="odom"), E.INVALID_REQUEST, "odom"),
        (dict(time_limit=-1.0), E.INVALID_REQUEST, "allowed_planning_time"),
    ]
    for kwargs, code, text in cases:
        response = client.request(**kwargs)
        assert response.error_code == code, (kwargs, response.error_code, response.error_msg)
        assert text in response.error_msg and len(response.path.poses) == 0
    assert client.request().error_code == E.NONE
    assert client.proc.alive()


def test_impossible_problem_is_proven_by_eca(client):
    from maru_planner_interfaces.srv import PlanBasePath

    client.publish_map(map_msg(table1("impossible")), "map 60 x 40 cells")
    t0 = time.monotonic()
    response = client.request()
    assert response.error_code == PlanBasePath.Response.NO_PATH_PROVEN, response.error_msg
    assert response.deciding_stage == "ECA" and "enclosed" in response.error_msg
    assert time.monotonic() - t0 < 30


def test_bad_maps_are_rejected_and_a_good_one_recovers(client):
    from maru_planner_interfaces.srv import PlanBasePath

    E = PlanBasePath.Response
    client.publish_map(map_msg(table1("easy"), width=0, height=0, data=[]), "the last map was rejected")
    response = client.request()
    assert response.error_code == E.NO_MAP and "empty" in response.error_msg
    client.publish_map(map_msg(table1("easy"), data=[0] * 100), "the last map was rejected")
    response = client.request()
    assert response.error_code == E.NO_MAP and "100 values" in response.error_msg
    client.publish_map(map_msg(table1("easy")), "map 60 x 40 cells")
    response = client.request()
    assert response.error_code == E.NONE and response.deciding_stage == "BAA"
    assert client.proc.alive()


def test_budgets_hold_for_huge_footprints_maps_and_searches(client):
    """No request holds the node past its budget + 0.5 s; what cannot fit is refused with an estimate."""
    import numpy as np

    from maru_planner.base.grid import OccupancyGrid
    from maru_planner_interfaces.srv import PlanBasePath

    E = PlanBasePath.Response
    huge = [(50.0, 50.0), (-50.0, 50.0), (-50.0, -50.0), (50.0, -50.0)]
    client.publish_map(map_msg(table1("easy")), "map 60 x 40 cells")
    for planner_id in ("se2", "mspp", "astar", "tunnel", "biped_wall"):
        response = client.request(planner_id=planner_id, footprint=huge, time_limit=5.0)
        assert response.error_code in (E.START_OCCUPIED, E.INVALID_REQUEST), (planner_id, response.error_msg)
        assert response.planning_time <= 5.5
    big = OccupancyGrid(np.random.default_rng(0).random((2000, 2000)) < 0.001, 0.05)
    client.publish_map(map_msg(big), "map 2000 x 2000 cells")
    refused = client.request(
        start=(10.0, 10.0, 0.0), goal=(90.0, 90.0, 0.0), planner_id="se2", footprint=huge, time_limit=5.0
    )
    assert refused.error_code in (E.INVALID_REQUEST, E.START_OCCUPIED, E.TIMEOUT), refused.error_msg
    assert refused.planning_time <= 5.5
    too_big = client.request(start=(10.0, 10.0, 0.0), goal=(90.0, 90.0, 0.0), planner_id="se2", time_limit=1.0)
    assert too_big.error_code == E.INVALID_REQUEST and "GB, over the 2 GB limit" in too_big.error_msg
    for planner_id in ("biped_wall", "biped_track", "mspp_local", "tunnel"):
        slow = client.request(start=(10.0, 10.0, 0.0), goal=(90.0, 90.0, 0.0), planner_id=planner_id, time_limit=1.0)
        assert slow.error_code in (E.TIMEOUT, E.NONE, E.NO_VALID_PATH), (planner_id, slow.error_msg)
        assert slow.planning_time <= 1.5, (planner_id, slow.planning_time)
    client.publish_map(map_msg(table1("easy")), "map 60 x 40 cells")
    assert client.request().error_code == E.NONE and client.proc.alive()


def test_a_base_planner_registered_from_outside_is_served_by_the_node(node_process, spinning_node, monkeypatch):
    from maru_planner_interfaces.srv import PlanBasePath

    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(TEST_DIR), os.environ.get("PYTHONPATH")])))
    proc = node_process(
        "toy_base_planner", ["node", "--ros-args", "-r", "__ns:=/toy", "-p", f"planner_id:={TOY_PLANNER}"]
    )
    client = Client(spinning_node, proc, "/toy")  # its own namespace: the module's node serves the same names
    client.publish_map(map_msg(table1("easy")), "map 60 x 40 cells")
    response = client.request(start=(1.0, 2.0, 0.0), goal=(2.0, 2.0, 0.0))  # the node's default: the toy
    assert response.error_code == PlanBasePath.Response.NONE, response.error_msg
    assert response.error_msg == "straight segment is free" and len(response.path.poses) >= 2
    through_wall = client.request(start=(1.0, 2.0, 0.0), goal=(5.5, 0.6, 0.0), planner_id=TOY_PLANNER)
    assert through_wall.error_code == PlanBasePath.Response.NO_VALID_PATH, through_wall.error_msg
    assert client.request(planner_id="mspp").error_code == PlanBasePath.Response.NONE
    assert proc.alive()
