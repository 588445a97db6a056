"""base_planner_node end to end for the tunnel planner and the two biped planners (PlanBasePath by planner id)."""

from __future__ import annotations

import json
import math

import pytest
import yaml
from conftest import BaseNodeClient

from maru_planner.base.biped import load_world, map_3d_to_2d
from maru_planner.base.grid import OccupancyGrid
from maru_planner.paths import config_path
from maru_planner.ros.reactive_conversions import pose_stamped_msg

pytestmark = pytest.mark.ros

NODE_MODULE = "maru_planner.ros.base_planner_node"
HOUSE_START, HOUSE_GOAL = (2.5, 21.0, 0.0), (22.0, 3.0, 0.0)
WORLD = "worlds/biped/corridor_narrow.yaml"
DISC_025 = [(0.25 * math.cos(a), 0.25 * math.sin(a)) for a in [k * math.pi / 4 for k in range(8)]]


@pytest.fixture(scope="module")
def node(node_process, tmp_path_factory):
    params = yaml.safe_load(config_path("base_planner.yaml").read_text())
    params["/**"]["ros__parameters"]["biped_world"] = WORLD
    path = tmp_path_factory.mktemp("params") / "base_planner.yaml"
    path.write_text(yaml.safe_dump(params))
    return node_process(NODE_MODULE, ["--ros-args", "--params-file", str(path)])


class Client(BaseNodeClient):
    def request(self, planner_id, start, goal, footprint=()):
        from geometry_msgs.msg import Point32

        from maru_planner_interfaces.srv import PlanBasePath

        req = PlanBasePath.Request()
        req.planner_id = planner_id
        req.footprint = [Point32(x=float(x), y=float(y)) for x, y in footprint]
        req.start, req.goal = pose_stamped_msg(start, "map", 0.0), pose_stamped_msg(goal, "map", 0.0)
        return self.spinning.call(self.plan_client, req, timeout=60)


@pytest.fixture
def client(spinning_node, node):
    return Client(spinning_node, node)


def test_tunnel_on_the_house_map(client):
    from maru_planner_interfaces.srv import PlanBasePath

    house = OccupancyGrid.from_yaml(config_path("maps", "house_250.yaml"))
    client.publish_grid(house, "map 250 x 250 cells")
    response = client.request("tunnel", HOUSE_START, HOUSE_GOAL, DISC_025)
    assert response.error_code == PlanBasePath.Response.NONE, response.error_msg
    assert response.deciding_stage.startswith("tunnel b=") and response.expansions > 0
    poses = response.path.poses
    assert len(poses) >= 2
    assert (poses[0].pose.position.x, poses[0].pose.position.y) == pytest.approx(HOUSE_START[:2])
    assert (poses[-1].pose.position.x, poses[-1].pose.position.y) == pytest.approx(HOUSE_GOAL[:2])
    stats = json.loads(response.stats_json)
    assert stats["attempts"] >= 1 and "tfp_expansions" in stats
    blocked = client.request("tunnel", HOUSE_START, (0.05, 0.05, 0.0), DISC_025)
    assert blocked.error_code == PlanBasePath.Response.GOAL_OCCUPIED
    assert client.proc.alive()


def test_biped_planners_on_the_world_parameter(client):
    from maru_planner_interfaces.srv import PlanBasePath

    world = load_world(config_path(WORLD))
    grid = map_3d_to_2d(world).to_occupancy_grid()
    client.publish_grid(grid, f"map {grid.width} x {grid.height} cells")
    track = client.request("biped_track", world.start, world.goal)
    assert track.error_code == PlanBasePath.Response.NO_VALID_PATH
    assert "K =" in track.error_msg  # K > L: the turning rule refuses
    wall = client.request("biped_wall", world.start, world.goal)
    assert wall.error_code == PlanBasePath.Response.NONE, wall.error_msg
    assert wall.deciding_stage == "virtual_wall" and len(wall.path.poses) > 50
    assert json.loads(wall.stats_json)["mapping"] == "3d_world"
    end = wall.path.poses[-1].pose
    assert (end.position.x, end.position.y) == pytest.approx(world.goal[:2])
    bad = client.request("biped_wall", (-3.0, 1.0, 0.0), world.goal)
    assert bad.error_code == PlanBasePath.Response.START_OUTSIDE_MAP
    assert client.proc.alive()
