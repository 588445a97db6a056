"""planning_node and robot_description: the URDF from robot_state_publisher's parameter or topic.

By default the node loads its URDF file and publishes no ``robot_description`` (robot_state_publisher
does); ``publish_robot_description`` brings the latched URDF back for setups without it. The
``robot_description`` / ``robot_description_semantic`` parameters replace the URDF/SRDF files, and
``robot_description_source:=topic`` reads the latched ``robot_description`` topic when configuring.
Each node runs in its own process and namespace. A narrowed ``waist_yaw`` limit (+-0.2 rad instead
of +-1.57) and an extra SRDF group show which description the node planned with.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
import yaml

from maru_planner.paths import urdf_path

pytestmark = pytest.mark.ros

WAIST_LIMIT = '<limit lower="-1.57" upper="1.57" effort="30.0" velocity="1.0"/>'
NARROW_WAIST_LIMIT = '<limit lower="-0.2" upper="0.2" effort="30.0" velocity="1.0"/>'
GROUP_JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
# the paper's start (test_planning_node) with the waist at 0, inside the narrowed limit
START = dict(zip(GROUP_JOINTS, (0.0, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25)))
NODE_MODULE = "maru_planner.ros.planning_node"


def narrow_waist_urdf() -> str:
    """Maru-1's URDF with waist_yaw limited to +-0.2 rad."""
    text = urdf_path("maru1_upper_body.urdf").read_text()
    waist = text.index('<joint name="waist_yaw"')
    assert text.index(WAIST_LIMIT, waist) < text.index("</joint>", waist), "waist_yaw's limit moved"
    return text[:waist] + text[waist:].replace(WAIST_LIMIT, NARROW_WAIST_LIMIT, 1)


def waist_group_srdf() -> str:
    """Maru-1's SRDF with one more group, ``waist_only``."""
    text = urdf_path("maru1_upper_body.srdf").read_text()
    return text.replace("</robot>", '  <group name="waist_only">\n    <joint name="waist_yaw"/>\n  </group>\n</robot>')


def node_args(namespace: str, tmp_path, **params) -> list[str]:
    """``--ros-args`` starting planning_node in ``namespace`` with ``params`` from a params file."""
    path = tmp_path / f"{namespace}.yaml"
    path.write_text(yaml.safe_dump({"/**": {"ros__parameters": {"scene_file": "none", "workers": 1, **params}}}))
    return ["--ros-args", "-r", f"__ns:=/{namespace}", "--params-file", str(path)]


@pytest.fixture(scope="module")
def tester(rclpy_session):
    from conftest import SpinningNode

    spinning = SpinningNode("robot_description_tests")
    yield spinning
    spinning.destroy()


def ready_client(tester, namespace: str, process):
    from maru_planner.ros.planning_client import PlanningClient

    client = PlanningClient(node=tester.node, namespace=f"/{namespace}")
    assert client.scene_client.wait_for_service(timeout_sec=120.0), process.log()
    client.wait_until_ready(timeout=120.0)
    return client


def plan_waist(client, angle: float, **fields):
    return client.plan({"waist_yaw": angle}, start=START, time_budget=5.0, **fields)


def latched_string_subscription(tester, topic: str, received: list):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    return tester.node.create_subscription(String, topic, received.append, qos)


def test_by_default_no_robot_description_is_published(node_process, tester, tmp_path):
    process = node_process(NODE_MODULE, node_args("rd_default", tmp_path))
    ready_client(tester, "rd_default", process)
    assert tester.node.get_publishers_info_by_topic("/rd_default/robot_description") == []
    assert tester.node.get_publishers_info_by_topic("/rd_default/planning_node/planned_trajectory") != []


def test_publish_robot_description_latches_the_urdf(node_process, tester, tmp_path):
    process = node_process(NODE_MODULE, node_args("rd_publish", tmp_path, publish_robot_description=True))
    ready_client(tester, "rd_publish", process)
    received: list = []
    latched_string_subscription(tester, "/rd_publish/robot_description", received)
    assert tester.wait_for(lambda: received, timeout=60.0), process.log()
    assert "maru1_upper_body" in received[0].data and "<robot" in received[0].data


def test_robot_description_parameters_replace_the_files(node_process, tester, tmp_path):
    from maru_planner_interfaces.msg import PlanningError

    description = {"robot_description": narrow_waist_urdf(), "robot_description_semantic": waist_group_srdf()}
    args = node_args("rd_param", tmp_path, default_group="waist_only", **description)
    process = node_process(NODE_MODULE, args)
    client = ready_client(tester, "rd_param", process)
    outside = plan_waist(client, 1.0)
    assert outside.error.code == PlanningError.INVALID_ROBOT_STATE, outside.error.message
    assert "waist_yaw" in outside.error.message
    inside = plan_waist(client, 0.15)
    assert inside.error.code == PlanningError.SUCCESS, inside.error.message
    assert list(inside.trajectory.joint_names) == ["waist_yaw"]  # the group of the SRDF parameter


def test_robot_description_topic_is_read_when_configuring(node_process, tester, tmp_path):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    from maru_planner_interfaces.msg import PlanningError

    # as robot_state_publisher publishes it: latched, before the planning node starts
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    publisher = tester.node.create_publisher(String, "/rd_topic/robot_description", qos)
    publisher.publish(String(data=narrow_waist_urdf()))
    process = node_process(NODE_MODULE, node_args("rd_topic", tmp_path, robot_description_source="topic"))
    client = ready_client(tester, "rd_topic", process)
    outside = plan_waist(client, 1.0, group="upper_body")
    assert outside.error.code == PlanningError.INVALID_ROBOT_STATE, outside.error.message
    assert "robot_description" in process.log()
    tester.node.destroy_publisher(publisher)


def test_no_urdf_on_the_topic_is_one_line_and_a_non_zero_exit(tmp_path):
    args = node_args("rd_nothing", tmp_path, robot_description_source="topic", robot_description_timeout=0.5)
    run = subprocess.run([sys.executable, "-m", NODE_MODULE, *args], capture_output=True, text=True, timeout=300)
    output = (run.stdout + run.stderr).strip()
    assert run.returncode == 2, output
    assert len(output.splitlines()) == 1 and "Traceback" not in output, output
    assert "/rd_nothing/robot_description" in output and "robot_state_publisher" in output, output
