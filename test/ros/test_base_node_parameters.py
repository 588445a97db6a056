"""base_planner_node parameters: descriptors, namespaced YAML, run-time changes applied or rejected, bad start-up."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
import yaml
from conftest import BaseNodeClient

from maru_planner.base.scenes import table1
from maru_planner.paths import config_path
from maru_planner.ros.reactive_conversions import pose_stamped_msg

pytestmark = pytest.mark.ros

NODE_MODULE = "maru_planner.ros.base_planner_node"
NS = "/robot1"
START, GOAL = (1.0, 2.0, 0.0), (5.0, 2.0, 0.0)


@pytest.fixture(scope="module")
def node(node_process, tmp_path_factory):
    params = yaml.safe_load(config_path("base_planner.yaml").read_text())
    params["/**"]["ros__parameters"]["planner_id"] = "se2"
    params["/**"]["ros__parameters"]["headings"] = 16
    path = tmp_path_factory.mktemp("params") / "base_planner.yaml"
    path.write_text(yaml.safe_dump(params))
    return node_process(NODE_MODULE, ["--ros-args", "-r", f"__ns:={NS}", "--params-file", str(path)])


class Client(BaseNodeClient):
    def __init__(self, spinning, proc):
        from rcl_interfaces.srv import DescribeParameters, SetParameters

        super().__init__(spinning, proc, namespace=NS)
        self.set_client = spinning.node.create_client(SetParameters, f"{NS}/base_planner_node/set_parameters")
        self.describe_client = spinning.node.create_client(
            DescribeParameters, f"{NS}/base_planner_node/describe_parameters"
        )

    def request(self, planner_id="", time_limit=0.0, goal=GOAL):
        from maru_planner_interfaces.srv import PlanBasePath

        req = PlanBasePath.Request()
        req.planner_id = planner_id
        req.start, req.goal = pose_stamped_msg(START, "map", 0.0), pose_stamped_msg(goal, "map", 0.0)
        req.allowed_planning_time = time_limit
        return self.spinning.call(self.plan_client, req, timeout=60)

    def set(self, name, value):
        """(successful, reason) of setting one parameter."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter

        req = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
        result = self.spinning.call(self.set_client, req, timeout=30).results[0]
        return result.successful, result.reason

    def describe(self, name):
        from rcl_interfaces.srv import DescribeParameters

        request = DescribeParameters.Request(names=[name])
        return self.spinning.call(self.describe_client, request, timeout=30).descriptors[0]


def _map_with_soft_wall():
    """Table I 'easy' plus a wall of value-50 cells across the passage (an obstacle only below threshold 50)."""
    from builtin_interfaces.msg import Time

    from maru_planner.ros.base_conversions import grid_to_msg

    grid = table1("easy")
    msg = grid_to_msg(grid, grid.occupied, Time(), "map")
    data = list(msg.data)
    for row in range(1, grid.height - 1):
        data[row * grid.width + 40] = 50
    msg.data = data
    return msg


@pytest.fixture
def client(spinning_node, node):
    c = Client(spinning_node, node)
    c.publish_map(_map_with_soft_wall(), "map 60 x 40 cells")
    return c


def test_namespaced_yaml_is_honoured_and_parameters_have_descriptors(client):
    from maru_planner_interfaces.srv import PlanBasePath

    response = client.request()
    assert response.error_code == PlanBasePath.Response.NONE, response.error_msg
    assert response.deciding_stage == "full" and json.loads(response.stats_json)["headings"] == 16
    headings = client.describe("headings")
    assert headings.integer_range[0].from_value == 1 and headings.integer_range[0].to_value == 3600
    assert "heading" in headings.description
    assert client.describe("allowed_planning_time").floating_point_range[0].to_value == 3600.0
    assert client.describe("map_topic").read_only


def test_run_time_changes_apply_to_the_next_answer(client):
    from maru_planner_interfaces.srv import PlanBasePath

    E = PlanBasePath.Response
    assert client.set("headings", 8) == (True, "")
    assert json.loads(client.request().stats_json)["headings"] == 8
    assert client.set("planner_id", "astar") == (True, "")
    assert client.request().deciding_stage == "astar"
    assert client.set("occupied_threshold", 40) == (True, "")  # the value-50 wall now blocks
    assert client.request().error_code == E.NO_VALID_PATH
    assert client.set("occupied_threshold", 65) == (True, "")
    assert client.request().error_code == E.NONE
    assert client.set("footprint", [0.1, 0.1, -0.1, 0.1, -0.1, -0.1, 0.1, -0.1]) == (True, "")
    assert json.loads(client.request(planner_id="tunnel").stats_json)["expansions"] > 0
    assert client.set("planner_id", "se2") == (True, "")
    assert client.set("allowed_planning_time", 0.001) == (True, "")
    assert client.request().error_code in (E.TIMEOUT, E.NONE)  # 1 ms: the budget is the node's now
    assert client.set("allowed_planning_time", 10.0) == (True, "")
    assert client.set("footprint", [0.45, 0.15, -0.45, 0.15, -0.45, -0.15, 0.45, -0.15]) == (True, "")


@pytest.mark.parametrize(
    "name, value, reason",
    [
        ("headings", -3, "headings out of range"),
        ("headings", "abc", "Wrong parameter type"),
        ("planner_id", "bogus", "unknown base planner 'bogus'"),
        ("footprint", [1.0, 2.0, 3.0], "x, y pairs"),
        ("footprint", [0.0, 0.0, 1.0, 0.0, 2.0, 0.0], "zero area"),
        ("allowed_planning_time", 0.0, "allowed_planning_time"),
        ("occupied_threshold", 101, "occupied_threshold"),
        ("biped_world", "no/such/world.yaml", "not found"),
        ("map_topic", "other_map", "read-only"),
    ],
)
def test_bad_changes_are_rejected_with_a_reason_and_later_requests_work(client, name, value, reason):
    from maru_planner_interfaces.srv import PlanBasePath

    ok, why = client.set(name, value)
    assert not ok and reason in why, why
    response = client.request(planner_id="mspp")
    assert response.error_code == PlanBasePath.Response.NONE, response.error_msg
    assert client.proc.alive()


@pytest.mark.parametrize(
    "args, needle",
    [
        (["-p", "headings:=abc"], "headings"),
        (["-p", "headings:=-3"], "headings"),
        (["-p", "planner_id:=bogus"], "unknown base planner 'bogus'"),
        (["-p", "footprint:=[1.0, 2.0, 3.0]"], "pairs"),
    ],
)
def test_wrong_start_up_parameters_are_one_line(args, needle):
    out = subprocess.run(
        [sys.executable, "-m", NODE_MODULE, "--ros-args", *args], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 2, out.stderr
    text = out.stderr + out.stdout
    assert "Traceback" not in text and needle in text, text
    assert len([line for line in out.stderr.splitlines() if line.strip()]) == 1, out.stderr
