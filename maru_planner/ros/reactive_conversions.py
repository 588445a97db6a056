"""ROS messages <-> the reactive core's plain types (poses as (x, y, θ), numpy arrays, LaserScanData).

Both directions are here: the node reads LaserScan / Odometry / Path /
PoseStamped (each checked against the core's limits: a bad message raises
ScanError or InputError naming the field, sizes before any conversion) and
writes Twist / Path / JointTrajectory / MarkerArray; the bag recorder and the
closed-loop test write LaserScan / Odometry / Path / PoseStamped from the
simulator. Nothing here holds state.
"""

from __future__ import annotations

import importlib
import math
from typing import Literal

import numpy as np
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import LaserScan
from std_msgs.msg import ColorRGBA
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import Marker, MarkerArray

from maru_planner.reactive import LaserScanData, ScanError
from maru_planner.reactive.inputs import Pose2D, check_path_size, planar_pose, yaw_from_quaternion
from maru_planner.reactive.scan import check_scan_size

NS_PER_S = 1_000_000_000


# ---------------------------------------------------------------- time and angles
def stamp_to_ns(stamp: Time) -> int:
    return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)


def stamp_to_s(stamp: Time) -> float:
    return stamp_to_ns(stamp) / NS_PER_S


def ns_to_stamp(ns: int) -> Time:
    ns = int(ns)
    return Time(sec=ns // NS_PER_S, nanosec=ns % NS_PER_S)


def s_to_stamp(seconds: float) -> Time:
    return ns_to_stamp(round(seconds * NS_PER_S))


def quaternion_from_yaw(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


# ---------------------------------------------------------------- LaserScan
def scan_from_msg(msg: LaserScan, stamp: float | None = None) -> LaserScanData:
    """LaserScan -> LaserScanData; raises ScanError when malformed. ``stamp`` overrides the header's.

    The core checks angles, increment, range limits and the beam count against
    angle_max; the intensities (unused, but a sign of a broken driver) are checked here.
    """
    n = len(msg.ranges)
    check_scan_size(n)
    if len(msg.intensities) not in (0, n):
        raise ScanError(f"LaserScan has {len(msg.intensities)} intensities for {n} ranges")
    return LaserScanData(
        angle_min=float(msg.angle_min),
        angle_increment=float(msg.angle_increment),
        ranges=np.asarray(msg.ranges, dtype=float),
        range_min=float(msg.range_min),
        range_max=float(msg.range_max),
        stamp=stamp_to_s(msg.header.stamp) if stamp is None else float(stamp),
        angle_max=float(msg.angle_max),
    )


def scan_msg(scan: LaserScanData, frame_id: str, scan_time: float = 0.0) -> LaserScan:
    """LaserScanData -> LaserScan stamped with ``scan.stamp`` (seconds)."""
    ranges = np.asarray(scan.ranges, dtype=np.float32)
    msg = LaserScan()
    msg.header.frame_id = frame_id
    msg.header.stamp = s_to_stamp(scan.stamp)
    msg.angle_min = float(scan.angle_min)
    msg.angle_increment = float(scan.angle_increment)
    msg.angle_max = float(scan.angle_min + scan.angle_increment * (len(ranges) - 1))
    msg.time_increment = 0.0
    msg.scan_time = float(scan_time)
    msg.range_min = float(scan.range_min)
    msg.range_max = float(scan.range_max)
    msg.ranges = ranges.tolist()
    return msg


# ---------------------------------------------------------------- poses, odometry, paths
def planar_pose_from_msg(pose: Pose, what: str) -> Pose2D:
    """geometry_msgs/Pose -> (x, y, yaw); InputError naming ``what`` for NaN/inf, far or non-unit values."""
    q = pose.orientation
    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w, f"{what}.orientation")
    return planar_pose(pose.position.x, pose.position.y, yaw, f"{what}.position")


def pose_from_odom(msg: Odometry) -> Pose2D:
    return planar_pose_from_msg(msg.pose.pose, "odom.pose.pose")


def odom_msg(pose: Pose2D, v: float, w: float, stamp_s: float, odom_frame: str, base_frame: str) -> Odometry:
    """A planar Odometry message: pose in ``odom_frame``, twist in ``base_frame``."""
    msg = Odometry()
    msg.header.stamp = s_to_stamp(stamp_s)
    msg.header.frame_id = odom_frame
    msg.child_frame_id = base_frame
    msg.pose.pose.position.x, msg.pose.pose.position.y = float(pose[0]), float(pose[1])
    msg.pose.pose.orientation = quaternion_from_yaw(float(pose[2]))
    msg.twist.twist.linear.x = float(v)
    msg.twist.twist.angular.z = float(w)
    return msg


def pose_from_pose_stamped(msg: PoseStamped, what: str = "goal_pose.pose") -> Pose2D:
    return planar_pose_from_msg(msg.pose, what)


def pose_stamped_msg(pose: Pose2D, frame_id: str, stamp_s: float) -> PoseStamped:
    msg = PoseStamped()
    msg.header.frame_id = frame_id
    msg.header.stamp = s_to_stamp(stamp_s)
    msg.pose.position.x, msg.pose.position.y = float(pose[0]), float(pose[1])
    msg.pose.orientation = quaternion_from_yaw(float(pose[2]))
    return msg


def path_pose_count(raw: bytes) -> int:
    """The pose count of a serialized nav_msgs/Path (little- or big-endian CDR), read without decoding the poses:
    a node refuses an oversized plan at this cost. -1 if ``raw`` is too short to be a Path."""
    if len(raw) < 20:
        return -1
    order: Literal["little", "big"] = "little" if raw[1] == 1 else "big"  # encapsulation 0x0001 CDR_LE, 0x0000 BE
    frame_length = int.from_bytes(raw[12:16], order)  # after the 4-byte encapsulation and the 8-byte stamp
    offset = 16 + frame_length
    offset += -(offset - 4) % 4  # the count is 4-aligned, counted from after the encapsulation
    if offset + 4 > len(raw):
        return -1
    return int.from_bytes(raw[offset : offset + 4], order)


def path_points_from_msg(msg: Path) -> np.ndarray:
    """nav_msgs/Path -> (n, 3) array of x, y, θ."""
    check_path_size(len(msg.poses), "plan")
    poses = [planar_pose_from_msg(p.pose, f"plan.poses[{i}].pose") for i, p in enumerate(msg.poses)]
    return np.array(poses, dtype=float).reshape(-1, 3)


def path_msg(points: np.ndarray, frame_id: str, stamp_s: float) -> Path:
    """(n, 2) or (n, 3) points -> nav_msgs/Path; without θ each pose faces the next point."""
    points = np.asarray(points, dtype=float)
    points = points.reshape(len(points), -1) if points.size else np.zeros((0, 2))
    if points.shape[1] >= 3:
        headings = points[:, 2]
    else:
        deltas = np.diff(points[:, :2], axis=0)
        headings = np.arctan2(deltas[:, 1], deltas[:, 0]) if len(deltas) else np.zeros(0)
        headings = np.append(headings, headings[-1] if len(headings) else 0.0)
    msg = Path()
    msg.header.frame_id = frame_id
    msg.header.stamp = s_to_stamp(stamp_s)
    msg.poses = [pose_stamped_msg((x, y, th), frame_id, stamp_s) for (x, y), th in zip(points[:, :2], headings)]
    return msg


# ---------------------------------------------------------------- commands
def twist_msg(v: float, w: float) -> Twist:
    msg = Twist()
    msg.linear.x = float(v)
    msg.angular.z = float(w)
    return msg


def twist_stamped_msg(v: float, w: float, frame_id: str, stamp_s: float) -> TwistStamped:
    msg = TwistStamped()
    msg.header.frame_id = frame_id
    msg.header.stamp = s_to_stamp(stamp_s)
    msg.twist = twist_msg(v, w)
    return msg


def arm_trajectory_msg(
    joint_names: list[str], positions: np.ndarray, steps: np.ndarray, period_s: float, stamp_s: float
) -> JointTrajectory:
    """One-point JointTrajectory: reach ``positions`` (after ``steps``) in one control period."""
    period_s = max(float(period_s), 1e-3)
    msg = JointTrajectory()
    msg.header.stamp = s_to_stamp(stamp_s)
    msg.joint_names = list(joint_names)
    point = JointTrajectoryPoint()
    point.positions = [float(p) for p in positions]
    point.velocities = [float(s) / period_s for s in steps]
    secs = int(period_s)
    point.time_from_start = Duration(sec=secs, nanosec=int(round((period_s - secs) * NS_PER_S)))
    msg.points = [point]
    return msg


# ---------------------------------------------------------------- markers
def _color(r: float, g: float, b: float, a: float = 1.0) -> ColorRGBA:
    return ColorRGBA(r=r, g=g, b=b, a=a)


def _marker(ns: str, marker_type: int, frame_id: str, stamp_s: float, scale: float, color: ColorRGBA) -> Marker:
    marker = Marker()
    marker.header.frame_id = frame_id
    marker.header.stamp = s_to_stamp(stamp_s)
    marker.ns, marker.id, marker.type, marker.action = ns, 0, marker_type, Marker.ADD
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = scale
    marker.color = color
    return marker


def _points(xy: np.ndarray) -> list[Point]:
    return [Point(x=float(x), y=float(y), z=0.0) for x, y in np.asarray(xy, dtype=float).reshape(-1, 2)]


def strip_markers(
    strip: np.ndarray,
    obstacle_points: np.ndarray,
    target: tuple[float, float] | np.ndarray | None,
    frame_id: str,
    stamp_s: float,
) -> MarkerArray:
    """The strip (line + vias), the obstacle points the forces came from, and the current target."""
    line = _marker("strip", Marker.LINE_STRIP, frame_id, stamp_s, 0.03, _color(0.1, 0.4, 1.0))
    line.points = _points(np.asarray(strip)[:, :2])
    vias = _marker("vias", Marker.SPHERE_LIST, frame_id, stamp_s, 0.08, _color(0.1, 0.4, 1.0))
    vias.points = line.points
    obstacles = _marker("obstacles", Marker.POINTS, frame_id, stamp_s, 0.05, _color(1.0, 0.2, 0.1))
    obstacles.points = _points(obstacle_points) if obstacle_points is not None else []
    markers = [line, vias, obstacles]
    if target is not None:
        goal = _marker("target", Marker.SPHERE, frame_id, stamp_s, 0.15, _color(0.1, 0.8, 0.2))
        goal.pose.position.x, goal.pose.position.y = float(target[0]), float(target[1])
        markers.append(goal)
    return MarkerArray(markers=markers)


# ---------------------------------------------------------------- bags
def message_class(msgtype: str):
    """The rclpy class of a full type name such as ``sensor_msgs/msg/LaserScan``."""
    parts = msgtype.split("/")
    if len(parts) != 3 or not all(parts):
        raise ValueError(f"message type {msgtype!r} is not of the form 'package/msg/Name'")
    try:
        return getattr(importlib.import_module(f"{parts[0]}.{parts[1]}"), parts[2])
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"no rclpy class for {msgtype} in this install ({exc})") from exc


def decode_bag_record(msgtype: str, rawdata: bytes):
    """CDR bytes from a bag -> the rclpy message, ready to publish."""
    return deserialize_message(bytes(rawdata), message_class(msgtype))
