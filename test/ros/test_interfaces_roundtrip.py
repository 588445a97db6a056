"""Round trip through a maru_planner_interfaces service over real rclpy on loopback."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.ros


def test_get_scene_service_round_trip(spinning_node):
    from shape_msgs.msg import SolidPrimitive

    from maru_planner_interfaces.msg import SceneObstacle
    from maru_planner_interfaces.srv import GetScene

    server_node = spinning_node.node

    def handle(_request, response):
        obstacle = SceneObstacle(name="desk")
        obstacle.shape.type = SolidPrimitive.BOX
        obstacle.shape.dimensions = [1.0, 2.0, 0.05]
        obstacle.pose.position.x = 0.5
        response.obstacles = [obstacle]
        response.scene_yaml = "frame: base_link"
        return response

    server_node.create_service(GetScene, "roundtrip_get_scene", handle)
    client = server_node.create_client(GetScene, "roundtrip_get_scene")
    response = spinning_node.call(client, GetScene.Request(), timeout=20.0)
    assert [o.name for o in response.obstacles] == ["desk"]
    assert list(response.obstacles[0].shape.dimensions) == [1.0, 2.0, 0.05]
    assert response.obstacles[0].pose.position.x == 0.5
    assert response.scene_yaml == "frame: base_link"


def test_planning_error_constants_follow_moveit():
    from maru_planner_interfaces.msg import PlanningError

    assert PlanningError.SUCCESS == 1
    failures = {
        name: getattr(PlanningError, name)
        for name in dir(PlanningError)
        if name.isupper() and name != "SUCCESS" and isinstance(getattr(PlanningError, name), int)
    }
    assert all(code < 0 for code in failures.values())
    assert len(set(failures.values())) == len(failures)


@pytest.mark.parametrize("name", ["PlanMotion", "PlanBasePath"])
def test_action_goal_and_result_mirror_the_service(name):
    """The actions are the services plus feedback (and PlanMotion's execution, an action-only option): a field
    added to one must be added to the other."""
    import importlib

    srv = getattr(importlib.import_module("maru_planner_interfaces.srv"), name)
    action = getattr(importlib.import_module("maru_planner_interfaces.action"), name)
    extra_goal = {"PlanMotion": {"execute": "boolean"}}.get(name, {})
    extra_result = {
        "PlanMotion": {
            "execution_error_code": "int32",
            "execution_error_string": "string",
            "execution_tracking_error": "double",
            "execution_time": "double",
        }
    }.get(name, {})
    assert action.Goal.get_fields_and_field_types() == {**srv.Request.get_fields_and_field_types(), **extra_goal}
    assert action.Result.get_fields_and_field_types() == {**srv.Response.get_fields_and_field_types(), **extra_result}
    feedback = action.Feedback.get_fields_and_field_types()
    assert feedback["stage"] == "string" and feedback["elapsed"] == "double"
