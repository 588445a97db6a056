"""Limits on poses, orientations and paths from outside (reactive/inputs.py), through the message conversions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.reactive.inputs import (
    MAX_COORDINATE,
    MAX_PATH_POSES,
    InputError,
    planar_pose,
    yaw_from_quaternion,
)

pytestmark = pytest.mark.ros  # the conversions need the message packages


@pytest.mark.parametrize("yaw", [0.0, 1.0, -2.5, math.pi - 1e-9])
def test_unit_quaternions_give_their_yaw(yaw):
    assert yaw_from_quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)) == pytest.approx(yaw)


@pytest.mark.parametrize(
    ("quaternion", "match"),
    [
        ((math.nan, 0.0, 0.0, 1.0), "not finite"),
        ((0.0, 0.0, 0.0, math.inf), "not finite"),
        ((0.0, 0.0, 0.0, 0.0), "norm 0"),
        ((0.0, 0.0, 1e300, 1e300), "not a unit quaternion"),
        ((0.0, 0.0, 0.0, 1.2), "not a unit quaternion"),
    ],
)
def test_bad_quaternions_are_refused(quaternion, match):
    with pytest.raises(InputError, match=match):
        yaw_from_quaternion(*quaternion, what="goal_pose.pose.orientation")


def test_poses_must_be_finite_and_near_the_origin():
    assert planar_pose(1, 2, 0.5) == (1.0, 2.0, 0.5)
    with pytest.raises(InputError, match="not finite"):
        planar_pose(math.nan, 0.0, 0.0)
    with pytest.raises(InputError, match="farther than"):
        planar_pose(0.0, -2 * MAX_COORDINATE, 0.0)


def test_bad_messages_raise_input_errors_naming_the_field():
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path

    from maru_planner.ros import reactive_conversions as conv

    goal = conv.pose_stamped_msg((1.0, 2.0, 0.3), "odom", 0.0)
    goal.pose.orientation.w = math.nan
    with pytest.raises(InputError, match=r"goal_pose\.pose\.orientation is not finite"):
        conv.pose_from_pose_stamped(goal)
    odom = conv.odom_msg((math.inf, 0.0, 0.0), 0.0, 0.0, 0.0, "odom", "base_link")
    with pytest.raises(InputError, match=r"odom\.pose\.pose\.position"):
        conv.pose_from_odom(odom)
    plan = conv.path_msg(np.array([[0.0, 0.0], [1e300, 0.0]]), "odom", 0.0)
    with pytest.raises(InputError, match=r"plan\.poses\[1\]\.pose\.position is farther"):
        conv.path_points_from_msg(plan)
    huge = Path(poses=[PoseStamped()] * (MAX_PATH_POSES + 1))
    with pytest.raises(InputError, match="at most"):
        conv.path_points_from_msg(huge)
