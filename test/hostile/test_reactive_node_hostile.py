"""reactive_node against hostile messages, through real rclpy publishers: nothing kills it, each is counted.

One node process (sim time, every warning logged) takes each bad message in turn; the test waits for
the node's warning naming it and for its counter in the status line to go up, then checks that a
good scan (and goal) still gives a sensible command.
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pytest
from reactive_helpers import (
    OBSTACLE,
    client_with_goal,
    odom,
    shipped_params,
    start_namespaced_node,
    synthetic_scan,
)

pytestmark = pytest.mark.ros

NS = "/hostile"
GOAL = (4.0, 0.0, 0.0)
_stamps = (10.0 + 0.1 * k for k in itertools.count())


@pytest.fixture(scope="module")
def node(node_process, tmp_path_factory):
    return start_namespaced_node(
        node_process,
        tmp_path_factory.mktemp("hostile_params"),
        NS,
        status_period=0.3,
        scan_timeout=600.0,
        warn_throttle_period=0.0,
    )


@pytest.fixture(scope="module")
def client(node, rclpy_session):
    yield from client_with_goal("hostile_client", NS, node, GOAL)


def counter(node, name: str) -> int:
    """The last value of counter ``name`` (e.g. ``dropped``, ``rejected goals``) in the node's status lines."""
    found = re.findall(rf"\b{name} (\d+)", node.log())
    return int(found[-1]) if found else -1


def expect_rejected(client, node, send, counter_name: str, message: str) -> None:
    """``send()`` a bad message; the node must warn with ``message`` and count it under ``counter_name``."""
    assert client.spinning.wait_for(lambda: counter(node, counter_name) >= 0, timeout=30), node.log()[-1500:]
    before, warnings_before = counter(node, counter_name), node.log().count(message)
    send()
    assert client.spinning.wait_for(lambda: node.log().count(message) > warnings_before, timeout=30), (
        f"no warning {message!r}:\n{node.log()[-1500:]}"
    )
    assert client.spinning.wait_for(lambda: counter(node, counter_name) == before + 1, timeout=30), (
        f"{counter_name} did not go from {before} to {before + 1}:\n{node.log()[-1500:]}"
    )
    assert node.alive()


def good_step(client):
    """A good odometry + scan pair; the answer must move the base towards the goal within the limits."""
    stamp = next(_stamps)
    twist = client.step(odom((0.0, 0.0, 0.0), stamp), synthetic_scan(stamp, [OBSTACLE]))
    limits = shipped_params()
    assert 0.0 < twist.linear.x <= limits["max_linear"] + 1e-9, twist
    assert abs(twist.angular.z) <= limits["max_angular"] + 1e-9
    return twist


def _goal(x=4.0, y=0.0, q=(0.0, 0.0, 0.0, 1.0)):
    from maru_planner.ros import reactive_conversions as conv

    msg = conv.pose_stamped_msg((0.0, 0.0, 0.0), "odom", 0.0)
    msg.pose.position.x, msg.pose.position.y = x, y
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = q
    return msg


BAD_GOALS = {
    "nan position": (_goal(x=math.nan), "goal_pose.pose.position is not finite"),
    "inf position": (_goal(y=-math.inf), "goal_pose.pose.position is not finite"),
    "far position": (_goal(x=1e300), "goal_pose.pose.position is farther than"),
    "nan quaternion": (_goal(q=(0.0, 0.0, math.nan, 1.0)), "goal_pose.pose.orientation is not finite"),
    "zero quaternion": (_goal(q=(0.0, 0.0, 0.0, 0.0)), "not a unit quaternion (norm 0)"),
    "huge quaternion": (_goal(q=(0.0, 0.0, 1e300, 1e300)), "not a unit quaternion"),
}


@pytest.mark.parametrize("case", list(BAD_GOALS))
def test_bad_goals_are_rejected_and_a_good_goal_still_works(case, client, node):
    from maru_planner.ros import reactive_conversions as conv

    msg, message = BAD_GOALS[case]
    expect_rejected(client, node, lambda: client.goal_pub.publish(msg), "rejected goals", message)
    good_step(client)
    client.send_and_confirm(client.goal_pub, conv.pose_stamped_msg(GOAL, "odom", 0.0), node, "goal (")
    good_step(client)


def _plan(points, q=None):
    from maru_planner.ros import reactive_conversions as conv

    msg = conv.path_msg(np.asarray(points, dtype=float), "odom", 0.0)
    if q is not None:
        o = msg.poses[-1].pose.orientation
        o.x, o.y, o.z, o.w = q
    return msg


BAD_PLANS = {
    "poses 1e300 apart": (_plan([[0.0, 0.0], [1e300, -1e300]]), "plan.poses[1].pose.position is farther"),
    "nan pose": (
        _plan([[0.0, 0.0, 0.0], [math.nan, 1.0, 0.0], [2.0, 0.0, 0.0]]),
        "plan.poses[1].pose.position is not finite",
    ),
    "too long for the strip": (_plan([[-9e4, -9e4], [9e4, 9e4], [-9e4, 9e4], [9e4, -9e4]]), "m long"),
    "one pose": (_plan([[1.0, 1.0]]), "plan has 1 poses"),
    "zero quaternion": (_plan([[0.0, 0.0], [3.0, 0.0]], q=(0.0, 0.0, 0.0, 0.0)), "not a unit quaternion"),
}


@pytest.mark.parametrize("case", list(BAD_PLANS))
def test_bad_plans_are_rejected_and_the_goal_stays(case, client, node):
    msg, message = BAD_PLANS[case]
    expect_rejected(client, node, lambda: client.plan_pub.publish(msg), "plans", message)
    good_step(client)


def _scan(**fields):
    scan = synthetic_scan(next(_stamps), [OBSTACLE])
    for name, value in fields.items():
        setattr(scan, name, value)
    return scan


BAD_SCANS = {
    "too few ranges": (lambda: _scan(ranges=[1.0] * 100), "ranges but"),
    "intensities of another length": (lambda: _scan(intensities=[1.0, 2.0]), "intensities"),
    "all ranges nan": (lambda: _scan(ranges=[math.nan] * 361), "all NaN"),
    "range_max < range_min": (lambda: _scan(range_min=5.0, range_max=1.0), "range limits invalid"),
    "angle_increment 0": (lambda: _scan(angle_increment=0.0), "angle_increment is 0"),
    "nan range_min": (lambda: _scan(range_min=math.nan), "range_min is not finite"),
    "huge array": (lambda: _scan(ranges=[1.0] * 200_001, angle_increment=1e-5), "at most"),
}


@pytest.mark.parametrize("case", list(BAD_SCANS))
def test_malformed_scans_are_dropped_and_counted(case, client, node):
    make, message = BAD_SCANS[case]
    expect_rejected(client, node, lambda: client.scan_pub.publish(make()), "dropped", message)
    good_step(client)


def test_a_scan_stamped_in_the_future_is_dropped_and_does_not_freeze_the_base(client, node):
    now = next(_stamps)
    client.publish_clock(round(now * 1e9))

    def send():
        client.odom_pub.publish(odom((0.0, 0.0, 0.0), now))
        client.scan_pub.publish(synthetic_scan(now + 1000.0, [OBSTACLE]))

    expect_rejected(client, node, send, "future", "dropped scan stamped 1000.")
    for _ in range(3):
        good_step(client)


def test_bad_odometry_is_dropped(client, node):
    from maru_planner.ros import reactive_conversions as conv

    bad = conv.odom_msg((0.0, 0.0, 0.0), 0.0, 0.0, next(_stamps), "odom", "base_link")
    bad.pose.pose.position.x = math.nan
    expect_rejected(client, node, lambda: client.odom_pub.publish(bad), "odometry", "dropped odometry: odom")
    future = conv.odom_msg((5.0, 5.0, 0.0), 0.0, 0.0, next(_stamps) + 1000.0, "odom", "base_link")
    expect_rejected(client, node, lambda: client.odom_pub.publish(future), "future", "dropped odometry stamped")
    good_step(client)


def test_no_message_killed_the_node_or_printed_a_traceback(client, node):
    good_step(client)
    assert node.alive()
    assert "Traceback" not in node.log()
    assert client.spinning.wait_for(lambda: counter(node, "callback errors") == 0, timeout=30)
