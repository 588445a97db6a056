"""Start arm_sim_node with config/arm_sim.yaml (ros2 launch maru_planner arm_sim.launch.py).

Arguments: ``params_file`` (default: the installed config/arm_sim.yaml), ``namespace``, ``scene_file``
(overrides the yaml's scene; empty keeps it), ``use_sim_time``, ``autostart`` (``false``: the node waits
unconfigured for a lifecycle manager) and ``rviz`` (``true``: rviz2 with config/rviz/planning.rviz, which shows
the robot as robot_state_publisher publishes it from ``joint_states``).
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
        "executable": "arm_sim_node",
        "name": "arm_sim_node",
        "namespace": LaunchConfiguration("namespace"),
        "output": "screen",
    }
    has_scene = PythonExpression(["'", scene_file, "' != ''"])
    no_scene = PythonExpression(["'", scene_file, "' == ''"])
    return LaunchDescription(
        [
            *common_arguments("arm_sim_node", "arm_sim.yaml", "planning.rviz"),
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
