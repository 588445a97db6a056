"""Planar ``/tf`` messages built with the ``rosbags`` typestore (tf2_msgs is not an rclpy package here)."""

from __future__ import annotations

import math
from typing import Any

from maru_planner.bag.rosbag_io import typestore

TF_MSGTYPE = "tf2_msgs/msg/TFMessage"


def _stamp(stamp_ns: int) -> Any:
    time_cls = typestore().types["builtin_interfaces/msg/Time"]
    return time_cls(sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000))


def planar_transform(parent: str, child: str, stamp_ns: int, x: float, y: float, yaw: float) -> Any:
    """A ``geometry_msgs/msg/TransformStamped`` for a pose in the plane (z = 0, rotation about z)."""
    types = typestore().types
    header = types["std_msgs/msg/Header"](stamp=_stamp(stamp_ns), frame_id=parent)
    translation = types["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=0.0)
    rotation = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))
    transform = types["geometry_msgs/msg/Transform"](translation=translation, rotation=rotation)
    return types["geometry_msgs/msg/TransformStamped"](header=header, child_frame_id=child, transform=transform)


def tf_message(transforms: list[Any]) -> Any:
    """A ``tf2_msgs/msg/TFMessage`` holding the given TransformStamped messages."""
    return typestore().types[TF_MSGTYPE](transforms=list(transforms))


def planar_pose_of(transform: Any) -> tuple[float, float, float]:
    """(x, y, yaw) of a planar TransformStamped."""
    t, q = transform.transform.translation, transform.transform.rotation
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    return float(t.x), float(t.y), yaw
