"""Start reactive_node with config/reactive.yaml (ros2 launch maru_planner reactive.launch.py).

Arguments: ``params_file`` (default: the installed config/reactive.yaml, keyed ``/**`` so it applies
in any namespace), ``namespace`` (every topic is relative, so a namespace moves them all), ``strip``
(``modified`` | ``plain``, overrides the file), ``use_sim_time`` (``true``: time from ``/clock``, e.g.
``ros2 bag play --clock``), ``autostart`` (``false``: the node waits unconfigured for a lifecycle
manager and commands nothing until activated), ``rviz`` (``true``: rviz2 with
config/rviz/reactive.rviz), and remappings for the robot's own topic names: ``scan_topic``, ``odom_topic``,
``plan_topic``, ``goal_topic``, ``cmd_vel_topic``.
"""

from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription
from maru_planner.ros.launch_args import common_arguments, common_overrides, rviz_node

REMAPPED = {
    "scan": ("scan_topic", "laser scans (sensor_msgs/LaserScan)"),
    "odom": ("odom_topic", "odometry (nav_msgs/Odometry)"),
    "plan": ("plan_topic", "initial path (nav_msgs/Path)"),
    "goal_pose": ("goal_topic", "goal (geometry_msgs/PoseStamped)"),
    "cmd_vel": ("cmd_vel_topic", "base command (geometry_msgs/Twist)"),
}


def generate_launch_description():
    arguments = [
        *common_arguments("reactive_node", "reactive.yaml", "reactive.rviz", "namespace of the node and its topics"),
        DeclareLaunchArgument("strip", default_value="modified", description="elastic strip: modified | plain"),
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
        parameters=[LaunchConfiguration("params_file"), {**common_overrides(), "strip": LaunchConfiguration("strip")}],
        remappings=[(topic, LaunchConfiguration(argument)) for topic, (argument, _) in REMAPPED.items()],
    )
    return LaunchDescription([*arguments, rviz_node("reactive.rviz"), node])
