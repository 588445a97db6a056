"""Start reactive_node with config/reactive.yaml (ros2 launch maru_planner reactive.launch.py).

Arguments: ``params_file`` (default: the installed config/reactive.yaml, keyed ``/**`` so it applies
in any namespace), ``namespace`` (every topic is relative, so a namespace moves them all), ``strip``
(``modified`` | ``plain``, overrides the file), ``use_sim_time`` (``true``: time from ``/clock``, e.g.
``ros2 bag play --clock``), ``autostart`` (``false``: the node waits unconfigured for a lifecycle
manager and commands nothing until activated), ``rviz`` (``true``: rviz2 with
config/rviz/reactive.rviz), and remappings for the robot's own topic names: ``scan_topic``, ``odom_topic``,
``plan_topic``, ``goal_topic``, ``cmd_vel_topic``.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
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
        DeclareLaunchArgument(
            "autostart", default_value="true", description="configure and activate at once (false: lifecycle)"
        ),
        DeclareLaunchArgument("rviz", default_value="false", description="start rviz2 with reactive.rviz"),
    ]
    arguments += [
        DeclareLaunchArgument(argument, default_value=topic, description=description)
        for topic, (argument, description) in REMAPPED.items()
    ]
    namespace = LaunchConfiguration("namespace")
    use_sim_time = LaunchConfiguration("use_sim_time")
    rviz = Node(
        package="rviz2",
        executable="rviz2",
        name="rviz2",
        namespace=namespace,
        arguments=["-d", os.path.join(share, "config", "rviz", "reactive.rviz")],
        parameters=[{"use_sim_time": use_sim_time}],
        condition=IfCondition(LaunchConfiguration("rviz")),
        output="screen",
    )
    node = Node(
        package="maru_planner",
        executable="reactive_node",
        name="reactive_node",
        namespace=namespace,
        output="screen",
        parameters=[
            LaunchConfiguration("params_file"),
            {"strip": LaunchConfiguration("strip"), "use_sim_time": use_sim_time,
             "autostart": LaunchConfiguration("autostart")},
        ],
        remappings=[(topic, LaunchConfiguration(argument)) for topic, (argument, _) in REMAPPED.items()],
    )
    return LaunchDescription([*arguments, rviz, node])
