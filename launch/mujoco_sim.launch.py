"""Start mujoco_sim_node with config/mujoco_sim.yaml (ros2 launch maru_planner mujoco_sim.launch.py).

Arguments: ``params_file`` (default: the installed config/mujoco_sim.yaml), ``namespace``, ``world`` (a public
BARN world 0..299, overrides the file), ``use_sim_time``, ``autostart`` (``false``: the node waits unconfigured
for a lifecycle manager) and ``rviz`` (``true``: rviz2 with config/rviz/reactive.rviz: the scan, odometry and
the strip of a reactive_node driving the simulated base).
"""

from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription
from maru_planner.ros.launch_args import common_arguments, common_overrides, rviz_node


def generate_launch_description():
    node = Node(
        package="maru_planner",
        executable="mujoco_sim_node",
        name="mujoco_sim_node",
        namespace=LaunchConfiguration("namespace"),
        output="screen",
        parameters=[LaunchConfiguration("params_file"), {**common_overrides(), "world": LaunchConfiguration("world")}],
    )
    return LaunchDescription(
        [
            *common_arguments("mujoco_sim_node", "mujoco_sim.yaml", "reactive.rviz"),
            DeclareLaunchArgument("world", default_value="0", description="public BARN world 0..299"),
            node,
            rviz_node("reactive.rviz"),
        ]
    )
