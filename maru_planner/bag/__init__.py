"""rosbag2 record/replay helpers on the pure-Python ``rosbags`` library (no rclpy)."""

from maru_planner.bag.rosbag_io import (
    BagError,
    BagMessage,
    BagSummary,
    BagWriter,
    read_messages,
    summarize,
    typestore,
)
from maru_planner.bag.tf import TF_MSGTYPE, planar_pose_of, planar_transform, tf_message

__all__ = [
    "BagError",
    "BagMessage",
    "BagSummary",
    "BagWriter",
    "TF_MSGTYPE",
    "planar_pose_of",
    "planar_transform",
    "read_messages",
    "summarize",
    "tf_message",
    "typestore",
]
