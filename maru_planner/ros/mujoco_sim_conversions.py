"""mujoco_sim_node's messages: the simulation's plain values -> /clock, /scan, /odom, /tf and the status line.

``tf2_msgs`` has no wheel here: ``scripts/build_interfaces.sh`` builds a TFMessage-only stand-in
(``interfaces/tf2_msgs``) unless a real one is importable; both have the same type name and fields.
"""

from __future__ import annotations

import json
import math

import numpy as np
from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock  # type: ignore[import-untyped]
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage  # type: ignore[import-untyped]

from maru_planner.barn.stack import laser_scan_data
from maru_planner.physics.base_sim import BaseSim
from maru_planner.physics.laser import Scan
from maru_planner.ros.reactive_conversions import odom_msg, quaternion_from_yaw, s_to_stamp, scan_msg


def clock_msg(seconds: float) -> Clock:
    return Clock(clock=s_to_stamp(seconds))


def laser_msg(scan: Scan, frame_id: str, scan_time: float) -> LaserScan:
    return scan_msg(laser_scan_data(scan), frame_id, scan_time)


def odometry_msg(sim: BaseSim, odom_frame: str, base_frame: str) -> Odometry:
    """The wheel odometry (it drifts), stamped with sim time."""
    x, y, yaw = (float(value) for value in sim.odometry.pose)
    v, w = sim.odometry.twist
    return odom_msg((x, y, yaw), float(v), float(w), sim.time, odom_frame, base_frame)


def truth_msg(sim: BaseSim, world_frame: str, base_frame: str) -> Odometry:
    """The ground truth (for scoring and pictures only), in the world's frame."""
    return odom_msg(sim.true_pose(), *sim.true_twist(), sim.time, world_frame, base_frame)


def tf_msg(sim: BaseSim, odom_frame: str, base_frame: str) -> TFMessage:
    """odom -> base_link from the odometry."""
    x, y, yaw = (float(value) for value in sim.odometry.pose)
    transform = TransformStamped()
    transform.header.stamp = s_to_stamp(sim.time)
    transform.header.frame_id = odom_frame
    transform.child_frame_id = base_frame
    transform.transform.translation.x, transform.transform.translation.y = x, y
    transform.transform.rotation = quaternion_from_yaw(yaw)
    return TFMessage(transforms=[transform])


def twist_command(msg: Twist) -> tuple[float, float]:
    """/cmd_vel -> (v, w); NaN or inf pass through (the simulation stops the robot and counts them)."""
    return float(msg.linear.x), float(msg.angular.z)


def status_msg(sim: BaseSim, steps: int, silent_steps: int) -> String:
    """One JSON line per step: sim time, ground truth, collisions, command faults (what a scorer reads)."""
    x, y, yaw = sim.true_pose()
    events = sim.events
    clearance = sim.clearance()
    status = {
        "time": round(sim.time, 6),
        "steps": steps,
        "truth": [round(x, 6), round(y, 6), round(yaw, 6)],
        "odom": [round(float(value), 6) for value in np.asarray(sim.odometry.pose)],
        "collided": sim.collided,
        "contacts": len(events.contacts),
        "first_contact": list(events.contacts[0]) if events.contacts else None,
        "clearance": round(clearance, 6) if math.isfinite(clearance) else None,
        "cmd_timeouts": events.cmd_timeouts,
        "first_timeout_s": events.first_timeout_s,
        "nan_commands": events.nan_commands,
        "silent_steps": silent_steps,
    }
    return String(data=json.dumps(status))
