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

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PythonExpression
from launch_ros.actions import Node

from launch import LaunchDescription


def generate_launch_description():
    share = get_package_share_directory("maru_planner")
    params_file = LaunchConfiguration("params_file")
    namespace = LaunchConfiguration("namespace")
    scene_file = LaunchConfiguration("scene_file")
    use_sim_time = LaunchConfiguration("use_sim_time")
    overrides = {"use_sim_time": use_sim_time, "autostart": LaunchConfiguration("autostart")}
    common = {
        "package": "maru_planner",
        "executable": "planning_node",
        "name": "planning_node",
        "namespace": namespace,
        "output": "screen",
    }
    has_scene = PythonExpression(["'", scene_file, "' != ''"])
    no_scene = PythonExpression(["'", scene_file, "' == ''"])
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value=os.path.join(share, "config", "planner.yaml"),
                description="planning_node parameters",
            ),
            DeclareLaunchArgument("namespace", default_value="", description="namespace of the node"),
            DeclareLaunchArgument("scene_file", default_value="", description="scene YAML (empty: from params)"),
            DeclareLaunchArgument("use_sim_time", default_value="false", description="time from /clock"),
            DeclareLaunchArgument(
                "autostart", default_value="true", description="configure and activate at once (false: lifecycle)"
            ),
            DeclareLaunchArgument("rviz", default_value="false", description="start rviz2 with planning.rviz"),
            Node(**common, parameters=[params_file, overrides], condition=IfCondition(no_scene)),
            Node(
                **common,
                parameters=[params_file, {**overrides, "scene_file": scene_file}],
                condition=IfCondition(has_scene),
            ),
            Node(
                package="rviz2",
                executable="rviz2",
                name="rviz2",
                namespace=namespace,
                arguments=["-d", os.path.join(share, "config", "rviz", "planning.rviz")],
                parameters=[{"use_sim_time": use_sim_time}],
                condition=IfCondition(LaunchConfiguration("rviz")),
                output="screen",
            ),
        ]
    )
