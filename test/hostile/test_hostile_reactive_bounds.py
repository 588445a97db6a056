"""reactive_node's bounds under oversized messages (issue 36): work per message, lag and memory stay bounded.

Twenty /plan messages of 20,000 poses (100,000 were accepted before: ~1.7 s each, the node then answered scans 9 s
old) are refused unread, each counted as ``oversized``; the scan sent right after them is answered as the next
update, with the base moving; a plan at ``max_plan_poses`` is still taken; the node's RSS stays far below 400 MB.
One node process (sim time) for the module.
"""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest
from hostile_inputs import rss_mb
from reactive_helpers import (
    OBSTACLE,
    client_with_goal,
    odom,
    start_namespaced_node,
    synthetic_scan,
)

pytestmark = pytest.mark.ros

NS = "/bounds"
GOAL = (4.0, 0.0, 0.0)
MAX_PLAN_POSES = 5000  # the node's default
OVERSIZED_POSES = 20_000
OVERSIZED_PLANS = 20
RSS_BOUND_MB = 400.0
_stamps = (10.0 + 0.1 * k for k in itertools.count())


@pytest.fixture(scope="module")
def node(node_process, tmp_path_factory):
    return start_namespaced_node(
        node_process,
        tmp_path_factory.mktemp("bounds_params"),
        NS,
        status_period=0.3,
        scan_timeout=600.0,
        warn_throttle_period=0.0,
    )


@pytest.fixture(scope="module")
def client(node, rclpy_session):
    yield from client_with_goal("bounds_client", NS, node, GOAL)


def _counter(node, name: str) -> int:
    found = re.findall(rf"\b{name} (\d+)", node.log())
    return int(found[-1]) if found else -1


def _serialized_plan(poses: int, frame_id_chars: int = 0) -> bytes:
    """A straight /plan to the goal, serialized; with ``frame_id_chars``, each pose's frame id that long."""
    from rclpy.serialization import serialize_message

    from maru_planner.ros import reactive_conversions as conv

    points = np.column_stack([np.linspace(0.0, GOAL[0], poses), np.zeros(poses), np.zeros(poses)])
    plan = conv.path_msg(points, "odom", 0.0)
    if frame_id_chars:
        for pose in plan.poses:
            pose.header.frame_id = "x" * frame_id_chars
    return serialize_message(plan)


def _good_step(client) -> float:
    stamp = next(_stamps)
    twist = client.step(odom((0.0, 0.0, 0.0), stamp), synthetic_scan(stamp, [OBSTACLE]))
    assert twist.linear.x > 0.0, twist
    return twist.linear.x


def test_oversized_plans_are_refused_unread_and_counted_and_the_next_scan_is_answered(client, node):
    _good_step(client)
    oversized = _serialized_plan(OVERSIZED_POSES)  # published as bytes: the test pays the conversion once
    for _ in range(OVERSIZED_PLANS):
        client.plan_pub.publish(oversized)
    # the node's plan queue holds one: each that reached it is refused before it is decoded
    assert client.spinning.wait_for(lambda: _counter(node, "oversized") >= 1, timeout=60), node.log()[-1500:]
    assert f"ignored /plan: {OVERSIZED_POSES} poses (max_plan_poses {MAX_PLAN_POSES}), not decoded" in node.log()
    _good_step(client)  # answered, not after seconds of plan decoding
    assert rss_mb(node.proc.pid) < RSS_BOUND_MB
    assert "initial path with" not in node.log()  # none was taken
    assert node.alive()


def test_a_plan_of_few_poses_with_huge_frame_ids_is_refused_unread(client, node):
    """bench/robustness.py's full run: 2,000 poses with long frame ids passed the pose count and took the node to
    1.1 GB once decoded."""
    client.plan_pub.publish(_serialized_plan(50, frame_id_chars=20_000))
    assert client.spinning.wait_for(lambda: "bytes for 50 poses (long names?), not decoded" in node.log(), timeout=60)
    _good_step(client)
    assert "initial path with 50 poses" not in node.log()
    assert node.alive()


def test_a_plan_at_the_limit_is_taken(client, node):
    client.plan_pub.publish(_serialized_plan(MAX_PLAN_POSES))
    assert client.spinning.wait_for(lambda: f"initial path with {MAX_PLAN_POSES} poses" in node.log(), timeout=60), (
        node.log()[-1500:]
    )
    _good_step(client)
    assert rss_mb(node.proc.pid) < RSS_BOUND_MB


def test_the_memory_of_a_huge_plan_is_given_back(client, node):
    """With rmw_fastrtps's default history memory, Fast DDS kept a buffer as large as the largest sample it ever
    received: one 200 MB /plan held 200 MB for the node's life. The loopback profile's DYNAMIC history memory
    frees it once the node has taken (and refused) it."""
    huge = _serialized_plan(3, frame_id_chars=40_000_000)
    before = rss_mb(node.proc.pid)
    client.plan_pub.publish(huge)
    assert client.spinning.wait_for(lambda: "bytes for 3 poses (long names?), not decoded" in node.log(), timeout=60)
    _good_step(client)
    assert rss_mb(node.proc.pid) - before < len(huge) / 1e6 / 4, (before, rss_mb(node.proc.pid))
