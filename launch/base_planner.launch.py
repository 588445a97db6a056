"""Start base_planner_node with config/base_planner.yaml (ros2 launch maru_planner base_planner.launch.py).

Arguments: ``params_file`` (default: the installed config/base_planner.yaml), ``namespace``,
``map_topic`` (where the nav_msgs/OccupancyGrid comes from, default ``map``), ``use_sim_time`` (time
from ``/clock``), ``autostart`` (``false``: the node waits unconfigured for a lifecycle manager) and
``rviz`` (``true``: rviz2 with config/rviz/base_planner.rviz).
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription


def generate_launch_description():
    share = get_package_share_directory("maru_planner")
    namespace = LaunchConfiguration("namespace")
    use_sim_time = LaunchConfiguration("use_sim_time")
    overrides = {
        "map_topic": LaunchConfiguration("map_topic"),
        "use_sim_time": use_sim_time,
        "autostart": LaunchConfiguration("autostart"),
    }
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value=os.path.join(share, "config", "base_planner.yaml"),
                description="base_planner_node parameters",
            ),
            DeclareLaunchArgument("namespace", default_value="", description="namespace of the node"),
            DeclareLaunchArgument("map_topic", default_value="map", description="occupancy grid topic"),
            DeclareLaunchArgument("use_sim_time", default_value="false", description="time from /clock"),
            DeclareLaunchArgument(
                "autostart", default_value="true", description="configure and activate at once (false: lifecycle)"
            ),
            DeclareLaunchArgument("rviz", default_value="false", description="start rviz2 with base_planner.rviz"),
            Node(
                package="maru_planner",
                executable="base_planner_node",
                name="base_planner_node",
                namespace=namespace,
                output="screen",
                parameters=[LaunchConfiguration("params_file"), overrides],
            ),
            Node(
                package="rviz2",
                executable="rviz2",
                name="rviz2",
                namespace=namespace,
                arguments=["-d", os.path.join(share, "config", "rviz", "base_planner.rviz")],
                parameters=[{"use_sim_time": use_sim_time}],
                condition=IfCondition(LaunchConfiguration("rviz")),
                output="screen",
            ),
        ]
    )
