"""Where ``planning_node``'s robot comes from: its parameters, or the latched ``robot_description`` topic of
``robot_state_publisher`` (waited for by a helper node while configuring)."""

from __future__ import annotations

import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.wait_for_message import wait_for_message
from std_msgs.msg import String

from maru_planner import errors
from maru_planner.ros.planning_parameters import NodeSettings
from maru_planner.runtime import DescriptionFiles, RobotDescription, RobotSource, description_source

LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)


def robot_source(node: Node, settings: NodeSettings, files: DescriptionFiles) -> tuple[RobotSource, str]:
    """The robot of the node's parameters (XML text written to ``files``) and one line saying where it came from."""
    if settings.robot_description_source == "topic" and settings.publish_robot_description:
        raise errors.InvalidParameter(
            "publish_robot_description would echo the robot_description topic it reads "
            "(robot_description_source topic); set one of them"
        )
    if settings.robot_file and settings.robot_description_source == "topic":
        raise errors.InvalidParameter(
            "robot_file names the robot's URDF; robot_description_source topic reads another: set one"
        )
    urdf_xml, urdf_from = settings.robot_description, "the robot_description parameter"
    if settings.robot_description_source == "topic":
        urdf_xml = wait_for_robot_description(node, settings.robot_description_timeout)
        urdf_from = "topic " + node.resolve_topic_name("robot_description")
    description = RobotDescription(
        urdf_xml=urdf_xml,
        srdf_xml=settings.robot_description_semantic,
        urdf_file=settings.robot_urdf,
        srdf_file=settings.robot_srdf,
        package_dirs=tuple(settings.package_dirs),
        urdf_from=urdf_from,
        robot_file=settings.robot_file,
    )
    return description_source(description, files)


def wait_for_robot_description(node: Node, timeout: float) -> str:
    """The URDF on ``node``'s latched ``robot_description`` topic (robot_state_publisher's), read by a helper node.

    The helper node (same context, not spun by any executor) keeps the wait off the node's executor,
    which may be running the configure transition that asks.
    """
    topic = node.resolve_topic_name("robot_description")
    reader = rclpy.create_node(
        f"{node.get_name()}_description_reader",
        namespace=node.get_namespace(),
        context=node.context,
        use_global_arguments=False,
        start_parameter_services=False,
        enable_rosout=False,
    )
    try:
        received, msg = wait_for_message(String, reader, topic, qos_profile=LATCHED, time_to_wait=timeout)
    finally:
        reader.destroy_node()
    if not received or not msg.data.strip():
        raise errors.InvalidParameter(
            f"robot_description_source is topic, but no URDF arrived on {topic} within {timeout} s "
            "(is robot_state_publisher running?)"
        )
    return msg.data
