"""What the package's launch files (``launch/*.launch.py``) share: the common arguments, overrides and RViz.

Every node's launch file declares ``params_file``, ``namespace``, ``use_sim_time``, ``autostart`` and
``rviz``, passes ``use_sim_time`` and ``autostart`` to its node and starts rviz2 with its own RViz
config when ``rviz:=true``. Imports only ``launch``/``launch_ros`` (no rclpy node is made).
"""

from __future__ import annotations

import os
from typing import Any

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PythonExpression
from launch_ros.actions import Node

PACKAGE = "maru_planner"


def common_arguments(
    node_name: str, params_yaml: str, rviz_config: str, namespace_description: str = "namespace of the node"
) -> list[DeclareLaunchArgument]:
    """``params_file`` (default: the installed ``config/<params_yaml>``), ``namespace``, ``use_sim_time``,
    ``autostart`` and ``rviz``."""
    return [
        DeclareLaunchArgument(
            "params_file", default_value=_config_file(params_yaml), description=f"{node_name} parameters"
        ),
        DeclareLaunchArgument("namespace", default_value="", description=namespace_description),
        DeclareLaunchArgument("use_sim_time", default_value="false", description="time from /clock"),
        DeclareLaunchArgument(
            "autostart", default_value="true", description="configure and activate at once (false: lifecycle)"
        ),
        DeclareLaunchArgument("rviz", default_value="false", description=f"start rviz2 with {rviz_config}"),
    ]


def common_overrides() -> dict[str, Any]:
    """The node parameters the common arguments set: ``use_sim_time`` and ``autostart``."""
    return {"use_sim_time": LaunchConfiguration("use_sim_time"), "autostart": LaunchConfiguration("autostart")}


def node_with_scene_argument(executable: str) -> list[Any]:
    """``scene_file`` declared and the node ``executable`` started with the params file and the common overrides;
    a non-empty ``scene_file`` overrides the params file's scene (an empty one keeps it)."""
    scene_file = LaunchConfiguration("scene_file")
    overrides = common_overrides()
    node = {
        "package": PACKAGE,
        "executable": executable,
        "name": executable,
        "namespace": LaunchConfiguration("namespace"),
        "output": "screen",
    }
    params_file = LaunchConfiguration("params_file")
    return [
        DeclareLaunchArgument("scene_file", default_value="", description="scene YAML (empty: from params)"),
        Node(
            **node,
            parameters=[params_file, overrides],
            condition=IfCondition(PythonExpression(["'", scene_file, "' == ''"])),
        ),
        Node(
            **node,
            parameters=[params_file, {**overrides, "scene_file": scene_file}],
            condition=IfCondition(PythonExpression(["'", scene_file, "' != ''"])),
        ),
    ]


def rviz_node(rviz_config: str) -> Node:
    """rviz2 with the installed ``config/rviz/<rviz_config>``, in the node's namespace, only with ``rviz:=true``."""
    return Node(
        package="rviz2",
        executable="rviz2",
        name="rviz2",
        namespace=LaunchConfiguration("namespace"),
        arguments=["-d", _config_file("rviz", rviz_config)],
        parameters=[{"use_sim_time": LaunchConfiguration("use_sim_time")}],
        condition=IfCondition(LaunchConfiguration("rviz")),
        output="screen",
    )


def _config_file(*parts: str) -> str:
    return os.path.join(get_package_share_directory(PACKAGE), "config", *parts)
