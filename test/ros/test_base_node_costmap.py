"""base_planner_node's cost map (Nav2's inflation layer, 0-100 scaled) and cost parameters, end to end."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import BaseNodeClient

from maru_planner.base.costmap import cost_layer, to_occupancy_values
from maru_planner.base.footprint import footprint_radii
from maru_planner.base.scenes import table1
from maru_planner.paths import config_path
from maru_planner.ros.reactive_conversions import pose_stamped_msg

pytestmark = pytest.mark.ros

NODE_MODULE = "maru_planner.ros.base_planner_node"
START, GOAL = (1.0, 2.0, 0.0), (5.0, 2.0, 0.0)
FOOTPRINT = np.array([[0.45, 0.15], [-0.45, 0.15], [-0.45, -0.15], [0.45, -0.15]])


@pytest.fixture(scope="module")
def node(node_process):
    return node_process(NODE_MODULE, ["--ros-args", "--params-file", str(config_path("base_planner.yaml"))])


class Client(BaseNodeClient):
    def __init__(self, spinning, proc):
        from nav_msgs.msg import OccupancyGrid
        from rcl_interfaces.srv import DescribeParameters, SetParameters

        super().__init__(spinning, proc)
        node = spinning.node
        self.costmaps = []
        node.create_subscription(OccupancyGrid, "/base_planner_node/costmap", self.costmaps.append, self.latched)
        self.set_client = node.create_client(SetParameters, "/base_planner_node/set_parameters")
        self.describe_client = node.create_client(DescribeParameters, "/base_planner_node/describe_parameters")

    def request(self, planner_id=""):
        from maru_planner_interfaces.srv import PlanBasePath

        req = PlanBasePath.Request()
        req.planner_id = planner_id
        req.start, req.goal = pose_stamped_msg(START, "map", 0.0), pose_stamped_msg(GOAL, "map", 0.0)
        return self.spinning.call(self.plan_client, req, timeout=60)

    def set(self, name, value):
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter

        req = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
        result = self.spinning.call(self.set_client, req, timeout=30).results[0]
        return result.successful, result.reason

    def describe(self, name):
        from rcl_interfaces.srv import DescribeParameters

        return self.spinning.call(
            self.describe_client, DescribeParameters.Request(names=[name]), timeout=30
        ).descriptors[0]

    def next_costmap(self, count: int):
        assert self.spinning.wait_for(lambda: len(self.costmaps) > count, timeout=30), self.proc.log()[-2000:]
        return self.costmaps[-1]


@pytest.fixture
def client(spinning_node, node):
    c = Client(spinning_node, node)
    c.publish_grid(table1("medium"), "map 60 x 40 cells")
    return c


def expected_values(inflation: float, scaling: float) -> list[int]:
    grid = table1("medium")
    r_in, r_out = footprint_radii(FOOTPRINT)
    return to_occupancy_values(cost_layer(grid, r_in, r_out, inflation, scaling).cost).ravel().tolist()


def test_costmap_is_nav2s_inflation_scaled_to_0_100(client):
    msg = client.next_costmap(0)
    assert msg.info.width == 60 and msg.info.height == 40 and msg.header.frame_id == "map"
    assert list(msg.data) == expected_values(0.55, 10.0)
    values = set(msg.data)
    assert {0, 99, 100} <= values and any(0 < v < 99 for v in values)


def test_costmap_follows_its_parameters_and_refuses_bad_ones(client):
    seen = len(client.costmaps)
    assert client.set("inflation_radius", 1.0) == (True, "")
    assert client.set("cost_scaling_factor", 2.0) == (True, "")
    assert client.spinning.wait_for(lambda: list(client.costmaps[-1].data) == expected_values(1.0, 2.0), timeout=30)
    assert len(client.costmaps) > seen
    ok, why = client.set("inflation_radius", 0.05)  # below the footprint's inscribed radius (0.15 m)
    assert not ok and "inscribed radius" in why, why
    ok, why = client.set("cost_scaling_factor", -1.0)
    assert not ok and "cost_scaling_factor" in why, why
    assert client.set("inflation_radius", 0.55) == (True, "")
    assert client.set("cost_scaling_factor", 10.0) == (True, "")


def test_cost_parameters_have_descriptors_and_reach_the_planners(client):
    from maru_planner_interfaces.srv import PlanBasePath

    desc = client.describe("inflation_radius")
    assert desc.floating_point_range[0].from_value == 0.0 and "Nav2" in desc.description
    multiplier = client.describe("astar.cost_travel_multiplier")
    assert "cost" in multiplier.description and multiplier.floating_point_range[0].from_value == 0.0
    assert client.set("astar.smooth", True) == (True, "")
    response = client.request(planner_id="astar")
    assert response.error_code == PlanBasePath.Response.NO_VALID_PATH  # the grown map of R_max is closed
    assert client.set("footprint", [0.1, 0.1, -0.1, 0.1, -0.1, -0.1, 0.1, -0.1]) == (True, "")
    response = client.request(planner_id="astar")
    assert response.error_code == PlanBasePath.Response.NONE, response.error_msg
    assert json.loads(response.stats_json)["smoothing"]["accepted"]
    ok, why = client.set("astar.cost_travel_multiplier", -1.0)
    assert not ok and "cost_travel_multiplier" in why
    assert client.set("astar.smooth", False) == (True, "")
    assert client.set("footprint", FOOTPRINT.ravel().tolist()) == (True, "")


def test_an_inflation_radius_below_the_footprint_is_refused_at_start_up():
    out = subprocess.run(
        [sys.executable, "-m", NODE_MODULE, "--ros-args", "-p", "inflation_radius:=0.05"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2 and "inscribed radius" in out.stderr, out.stderr
    assert "Traceback" not in out.stderr + out.stdout
