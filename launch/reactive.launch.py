"""Start reactive_node with config/reactive.yaml (ros2 launch maru_planner reactive.launch.py).

Arguments: ``params_file`` (default: the installed config/reactive.yaml, keyed ``/**`` so it applies
in any namespace), ``namespace`` (every topic is relative, so a namespace moves them all), ``strip``
(``modified`` | ``plain``, overrides the file), ``use_sim_time`` (``true``: time from ``/clock``, e.g.
``ros2 bag play --clock``), and remappings for the robot's own topic names: ``scan_topic``, ``odom_topic``,
``plan_topic``, ``goal_topic``, ``cmd_vel_topic``.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription

REMAPPED = {
    "scan": ("scan_topic", "laser scans (sensor_msgs/LaserScan)"),
    "odom": ("odom_topic", "odometry (nav_msgs/Odometry)"),
    "plan": ("plan_topic", "initial path (nav_msgs/Path)"),
    "goal_pose": ("goal_topic", "goal (geometry_msgs/PoseStamped)"),
    "cmd_vel": ("cmd_vel_topic", "base command (geometry_msgs/Twist)"),
}


def generate_launch_description():
    share = get_package_share_directory("maru_planner")
    arguments = [
        DeclareLaunchArgument(
            "params_file",
            default_value=os.path.join(share, "config", "reactive.yaml"),
            description="reactive_node parameters",
        ),
        DeclareLaunchArgument("namespace", default_value="", description="namespace of the node and its topics"),
        DeclareLaunchArgument("strip", default_value="modified", description="elastic strip: modified | plain"),
        DeclareLaunchArgument("use_sim_time", default_value="false", description="time from /clock"),
    ]
    arguments += [
        DeclareLaunchArgument(argument, default_value=topic, description=description)
        for topic, (argument, description) in REMAPPED.items()
    ]
    node = Node(
        package="maru_planner",
        executable="reactive_node",
        name="reactive_node",
        namespace=LaunchConfiguration("namespace"),
        output="screen",
        parameters=[
            LaunchConfiguration("params_file"),
            {"strip": LaunchConfiguration("strip"), "use_sim_time": LaunchConfiguration("use_sim_time")},
        ],
        remappings=[(topic, LaunchConfiguration(argument)) for topic, (argument, _) in REMAPPED.items()],
    )
    return LaunchDescription([*arguments, node])
