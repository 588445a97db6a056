"""Start arm_sim_node with config/arm_sim.yaml (ros2 launch maru_planner arm_sim.launch.py).

Arguments: ``params_file`` (default: the installed config/arm_sim.yaml), ``namespace``, ``scene_file``
(overrides the yaml's scene; empty keeps it), ``use_sim_time``, ``autostart`` (``false``: the node waits
unconfigured for a lifecycle manager) and ``rviz`` (``true``: rviz2 with config/rviz/planning.rviz, which shows
the robot as robot_state_publisher publishes it from ``joint_states``).
"""

from launch import LaunchDescription
from maru_planner.ros.launch_args import common_arguments, node_with_scene_argument, rviz_node


def generate_launch_description():
    return LaunchDescription(
        [
            *common_arguments("arm_sim_node", "arm_sim.yaml", "planning.rviz"),
            *node_with_scene_argument("arm_sim_node"),
            rviz_node("planning.rviz"),
        ]
    )
