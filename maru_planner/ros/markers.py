"""RViz markers of the planning node: scene obstacles and the hands' paths of the last plan."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numpy as np
from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from maru_planner.ros import planning_conversions as conv
from maru_planner.runtime.robot_state import configuration
from maru_planner.scene import shapes

OBSTACLE_COLOR = ColorRGBA(r=0.8, g=0.5, b=0.2, a=0.6)
HAND_COLORS = {"right": ColorRGBA(r=0.9, g=0.1, b=0.1, a=1.0), "left": ColorRGBA(r=0.1, g=0.3, b=0.9, a=1.0)}
DEFAULT_HAND_COLOR = ColorRGBA(r=0.1, g=0.7, b=0.1, a=1.0)
HAND_PATH_WIDTH = 0.01


def scene_markers(scene_dict: dict, frame_id: str, stamp) -> MarkerArray:
    """A DELETEALL followed by one marker per obstacle (namespace ``scene``), shaped by the shape table."""
    markers = MarkerArray()
    clear = Marker(action=Marker.DELETEALL)
    clear.header.frame_id = frame_id
    markers.markers.append(clear)
    for index, obstacle in enumerate(scene_dict.get("obstacles", [])):
        markers.markers.append(_obstacle_marker(obstacle, frame_id, stamp, index))
    return markers


def _obstacle_marker(obstacle: dict, frame_id: str, stamp, index: int) -> Marker:
    msg = conv.obstacle_to_msg(obstacle, frame_id)
    spec = shapes.shape(obstacle["type"], f"obstacle '{obstacle['name']}'")
    look = spec.marker(obstacle)
    marker = Marker(ns="scene", id=index, action=Marker.ADD, color=OBSTACLE_COLOR, text=obstacle["name"])
    marker.header.frame_id = frame_id
    marker.header.stamp = stamp
    marker.pose = msg.pose
    marker.type = getattr(Marker, look.type)
    marker.scale.x, marker.scale.y, marker.scale.z = (float(v) for v in look.scale)
    marker.mesh_resource = look.mesh_resource
    return marker


def hand_paths(robot, trajectory, start: dict[str, float]) -> dict[str, np.ndarray]:
    """Positions (n x 3) of each end effector along the trajectory (other joints held at ``start``)."""
    base = dict(start)
    paths: dict[str, list] = {side: [] for side in robot.end_effectors}
    for row in np.asarray(trajectory.positions, dtype=float):
        state = dict(base)
        state.update(zip(trajectory.joint_names, row, strict=True))
        q = configuration(robot, state)
        for side, frame in robot.end_effectors.items():
            paths[side].append(np.asarray(robot.frame_pose(q, frame))[:3, 3])
    return {side: np.array(points) for side, points in paths.items()}


def plan_markers(robot, trajectory, start: dict[str, float], frame_id: str, stamp) -> MarkerArray:
    """One LINE_STRIP per end effector along the trajectory (namespace ``hand_path``)."""
    markers = MarkerArray()
    for index, (side, points) in enumerate(sorted(hand_paths(robot, trajectory, start).items())):
        marker = Marker(ns="hand_path", id=index, type=Marker.LINE_STRIP, action=Marker.ADD, text=side)
        marker.header.frame_id = frame_id
        marker.header.stamp = stamp
        marker.pose.orientation.w = 1.0
        marker.scale.x = HAND_PATH_WIDTH
        marker.color = HAND_COLORS.get(side, DEFAULT_HAND_COLOR)
        marker.points = [Point(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in points]
        markers.markers.append(marker)
    return markers


class MarkerPublisher:
    """The planning node's ``~/markers``: the scene with the last plan's hand paths, sent after every change and
    to each new subscriber (:meth:`on_timer` looks for them); nothing is computed while no one listens.

    ``scene()`` is the current scene dict, ``now()`` a stamp; ``robot``'s pinocchio data is shared with its
    other users in the node, so the hand paths are computed under a lock.
    """

    def __init__(self, publisher: Any, robot: Any, frame: str, scene: Callable[[], dict], now: Callable[[], Any]):
        self._publisher, self._robot, self._frame = publisher, robot, frame
        self._scene, self._now = scene, now
        self._lock = threading.Lock()
        self._last_plan: MarkerArray | None = None
        self._subscribers = 0

    def reset_subscribers(self) -> None:
        """Send the scene to whoever listens at the next :meth:`on_timer` (on activation)."""
        self._subscribers = 0

    def on_timer(self) -> None:
        count = self._publisher.get_subscription_count()
        if count > self._subscribers:
            self.publish()
        self._subscribers = count

    def publish(self) -> None:
        if self._publisher.get_subscription_count() == 0:
            return
        markers = scene_markers(self._scene(), self._frame, self._now())
        with self._lock:
            if self._last_plan is not None:
                markers.markers.extend(self._last_plan.markers)
        self._publisher.publish(markers)

    def publish_plan(self, trajectory: Any, start: dict[str, float], frame: str, stamp: Any) -> None:
        """Keep ``trajectory``'s hand paths (from joint values ``start``) and publish, when someone listens."""
        if self._publisher.get_subscription_count() > 0:
            with self._lock:
                self._last_plan = plan_markers(self._robot, trajectory, start, frame, stamp)
            self.publish()
