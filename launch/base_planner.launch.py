"""Start base_planner_node with config/base_planner.yaml (ros2 launch maru_planner base_planner.launch.py).

Arguments: ``params_file`` (default: the installed config/base_planner.yaml), ``namespace``,
``map_topic`` (where the nav_msgs/OccupancyGrid comes from, default ``map``), ``use_sim_time`` (time
from ``/clock``), ``autostart`` (``false``: the node waits unconfigured for a lifecycle manager) and
``rviz`` (``true``: rviz2 with config/rviz/base_planner.rviz).
"""

from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription
from maru_planner.ros.launch_args import common_arguments, common_overrides, rviz_node


def generate_launch_description():
    return LaunchDescription(
        [
            *common_arguments("base_planner_node", "base_planner.yaml", "base_planner.rviz"),
            DeclareLaunchArgument("map_topic", default_value="map", description="occupancy grid topic"),
            Node(
                package="maru_planner",
                executable="base_planner_node",
                name="base_planner_node",
                namespace=LaunchConfiguration("namespace"),
                output="screen",
                parameters=[
                    LaunchConfiguration("params_file"),
                    {**common_overrides(), "map_topic": LaunchConfiguration("map_topic")},
                ],
            ),
            rviz_node("base_planner.rviz"),
        ]
    )
