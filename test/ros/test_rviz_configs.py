"""The shipped RViz configs show topics the nodes really have (published or subscribed)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml

REPO_ROOT = Path(__file__).resolve().parents[2]
RVIZ = REPO_ROOT / "config" / "rviz"
NODES = {
    "planning": "maru_planner.ros.planning_node",
    "reactive": "maru_planner.ros.reactive_node",
    "base_planner": "maru_planner.ros.base_planner_node",
}

pytestmark = pytest.mark.ros


def _topics(config: dict) -> set[str]:
    manager = config["Visualization Manager"]
    found = set()
    for display in manager["Displays"]:
        for key in ("Topic", "Description Topic"):
            if key in display:
                found.add(display[key]["Value"])
    for tool in manager.get("Tools", []):
        if "Topic" in tool:
            found.add(tool["Topic"]["Value"])
    return found


@pytest.mark.parametrize("name", sorted(NODES))
def test_rviz_config_is_valid_yaml_with_a_fixed_frame(name):
    config = yaml.safe_load((RVIZ / f"{name}.rviz").read_text())
    manager = config["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"]
    assert all(d["Class"].startswith("rviz_default_plugins/") for d in manager["Displays"])


@pytest.mark.parametrize("name", sorted(NODES))
def test_every_rviz_topic_exists_on_the_running_node(name, node_process, spinning_node):
    # /robot_description comes from robot_state_publisher; without one, planning_node publishes it on request
    args = ["--ros-args", "-p", "publish_robot_description:=true"] if name == "planning" else []
    process = node_process(NODES[name], args)
    wanted = _topics(yaml.safe_load((RVIZ / f"{name}.rviz").read_text())) - {"/goal_pose"} | (
        {"/goal_pose"} if name == "reactive" else set()
    )
    deadline = time.monotonic() + 60.0
    missing = wanted
    while time.monotonic() < deadline:
        assert process.alive(), process.log()[-2000:]
        present = {topic for topic, _types in spinning_node.node.get_topic_names_and_types()}
        missing = wanted - present
        if not missing:
            break
        time.sleep(0.2)
    assert not missing, f"{name}.rviz shows topics the node does not have: {sorted(missing)}"
