"""Start planning_node with config/planner.yaml (ros2 launch maru_planner planning.launch.py).

Arguments: ``params_file`` (default: the installed config/planner.yaml), ``namespace`` (services and
topics are relative, so a namespace moves them; the yaml is keyed ``/**/planning_node``, so it still
applies), ``scene_file`` (overrides the yaml's scene), ``use_sim_time`` (time from ``/clock``),
``autostart`` (``false``: the node waits unconfigured for a lifecycle manager) and ``rviz`` (``true``:
rviz2 with config/rviz/planning.rviz, which shows ``/robot_description`` as robot_state_publisher
publishes it). Networking comes from the environment the launch runs in (RMW_IMPLEMENTATION,
ROS_AUTOMATIC_DISCOVERY_RANGE, ...); with none of it set the node stays on loopback (see
docs/planning_node.md).
"""

from launch import LaunchDescription
from maru_planner.ros.launch_args import common_arguments, node_with_scene_argument, rviz_node


def generate_launch_description():
    return LaunchDescription(
        [
            *common_arguments("planning_node", "planner.yaml", "planning.rviz"),
            *node_with_scene_argument("planning_node"),
            rviz_node("planning.rviz"),
        ]
    )
