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

from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PythonExpression
from launch_ros.actions import Node

from launch import LaunchDescription
from maru_planner.ros.launch_args import common_arguments, common_overrides, rviz_node


def generate_launch_description():
    params_file = LaunchConfiguration("params_file")
    scene_file = LaunchConfiguration("scene_file")
    overrides = common_overrides()
    common = {
        "package": "maru_planner",
        "executable": "planning_node",
        "name": "planning_node",
        "namespace": LaunchConfiguration("namespace"),
        "output": "screen",
    }
    has_scene = PythonExpression(["'", scene_file, "' != ''"])
    no_scene = PythonExpression(["'", scene_file, "' == ''"])
    return LaunchDescription(
        [
            *common_arguments("planning_node", "planner.yaml", "planning.rviz"),
            DeclareLaunchArgument("scene_file", default_value="", description="scene YAML (empty: from params)"),
            Node(**common, parameters=[params_file, overrides], condition=IfCondition(no_scene)),
            Node(
                **common,
                parameters=[params_file, {**overrides, "scene_file": scene_file}],
                condition=IfCondition(has_scene),
            ),
            rviz_node("planning.rviz"),
        ]
    )
