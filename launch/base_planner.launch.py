"""Start base_planner_node with config/base_planner.yaml (ros2 launch maru_planner base_planner.launch.py).

Arguments: ``params_file`` (default: the installed config/base_planner.yaml), ``namespace``,
``map_topic`` (where the nav_msgs/OccupancyGrid comes from, default ``map``).
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription


def generate_launch_description():
    share = get_package_share_directory("maru_planner")
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value=os.path.join(share, "config", "base_planner.yaml"),
                description="base_planner_node parameters",
            ),
            DeclareLaunchArgument("namespace", default_value="", description="namespace of the node"),
            DeclareLaunchArgument("map_topic", default_value="map", description="occupancy grid topic"),
            Node(
                package="maru_planner",
                executable="base_planner_node",
                name="base_planner_node",
                namespace=LaunchConfiguration("namespace"),
                output="screen",
                parameters=[LaunchConfiguration("params_file"), {"map_topic": LaunchConfiguration("map_topic")}],
            ),
        ]
    )
