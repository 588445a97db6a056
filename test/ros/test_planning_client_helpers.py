"""PlanningClient's lifecycle and parameter helpers (the rclpy equivalents of ``ros2 lifecycle get/set`` and
``ros2 param get/set``) on one planning_node in this process (empty scene, one planning thread)."""

from __future__ import annotations

import pytest

from maru_planner.ros.planning_client import PlanningClient

pytestmark = pytest.mark.ros


@pytest.fixture(scope="module")
def client(tester):
    from maru_planner.ros.planning_node import BackgroundPlanningNode

    with BackgroundPlanningNode(namespace="/helpers", scene_file="none", workers=1, worker_processes=False):
        planning = PlanningClient(node=tester.node, namespace="/helpers")
        planning.wait_until_ready(timeout=60.0)
        yield planning


def test_lifecycle_state_and_transitions(client):
    assert client.get_state() == "active"
    assert client.change_state("deactivate") and client.get_state() == "inactive"
    assert not client.change_state("deactivate")  # no such transition from inactive
    assert client.change_state("activate") and client.get_state() == "active"
    with pytest.raises(ValueError, match="unknown transition 'launch'"):
        client.change_state("launch")


def test_parameters_read_and_set(client):
    assert client.get_parameters("workers", "scene_file") == {"workers": 1, "scene_file": "none"}
    with pytest.raises(KeyError, match="planning_node has no parameter 'no_such_parameter'"):
        client.get_parameters("workers", "no_such_parameter")
    assert client.set_parameters(default_attempts=3) == {}
    assert client.get_parameters("default_attempts") == {"default_attempts": 3}
    rejected = client.set_parameters(default_attempts=0, planning_frame="world")
    assert set(rejected) == {"default_attempts", "planning_frame"}
    assert "default_attempts" in rejected["default_attempts"] and rejected["planning_frame"]
    assert client.get_parameters("default_attempts", "planning_frame") == {
        "default_attempts": 3, "planning_frame": "base_link",
    }  # fmt: skip
