"""planning_node's ``view`` option through a real node (in this process, so the view's state can be read): the page
is served, the scene and /joint_states reach the view, and a served plan (or failure) is what the view holds."""

from __future__ import annotations

import urllib.request

import numpy as np
import pytest
from conftest import PAPER_GOAL, PAPER_START, SpinningNode

from maru_planner_interfaces.msg import PlanningError

pytestmark = pytest.mark.ros


@pytest.fixture(scope="module")
def planning(rclpy_session):
    from maru_planner.ros.planning_node import BackgroundPlanningNode

    overrides = {"scene_file": "none", "workers": 1, "worker_processes": False, "view": True, "view_port": 0}
    with BackgroundPlanningNode(namespace="viewed", **overrides) as background:
        yield background.node


@pytest.fixture(scope="module")
def client(planning):
    from maru_planner.ros.planning_client import PlanningClient

    spinning = SpinningNode("view_client")
    try:
        yield spinning, PlanningClient(node=spinning.node, namespace="/viewed")
    finally:
        spinning.destroy()


def _view(planning):
    assert planning._view is not None, "view: true made no view"
    return planning._view.view


def test_the_page_is_served_and_shows_the_live_scene_and_joint_states(planning, client):
    from sensor_msgs.msg import JointState

    spinning, planning_client = client
    with urllib.request.urlopen(_view(planning).url, timeout=10.0) as page:
        assert page.status == 200 and b"<html" in page.read().lower()
    pose = np.eye(4)
    pose[:3, 3] = [0.6, 0.0, 0.9]
    planning_client.add_obstacle("crate", "box", [0.1, 0.2, 0.3], pose)
    assert spinning.wait_for(lambda: _view(planning).scene_view.obstacle_names == ["crate"], timeout=5.0)
    publisher = spinning.node.create_publisher(JointState, "/joint_states", 10)
    column = planning.runtime.robot.joint_names.index("r_arm_j4")
    msg = JointState(name=["r_arm_j4"], position=[0.8])

    def shown() -> bool:
        publisher.publish(msg)  # the subscription may match after the first messages
        return abs(_view(planning).robot_view.q[column] - 0.8) < 1e-9

    assert spinning.wait_for(shown, timeout=10.0, period=0.05)
    planning_client.remove_obstacle("crate")
    assert spinning.wait_for(lambda: _view(planning).scene_view.obstacle_names == [], timeout=5.0)
    spinning.node.destroy_publisher(publisher)


def test_a_served_plan_is_what_the_view_shows_and_plays(planning, client):
    _, planning_client = client
    response = planning_client.plan(PAPER_GOAL, start=PAPER_START, time_budget=5.0, seed=1)
    assert response.error.code == PlanningError.SUCCESS, response.error.message
    view = _view(planning)
    assert view.trajectory is not None
    assert list(view.trajectory.joint_names) == list(response.trajectory.joint_names)
    assert view.status.content.startswith("**SUCCESS**") and "clearance" in view.status.content
    assert view.wait_played(timeout=20.0)
    columns = planning.runtime.robot.joint_indices(list(response.trajectory.joint_names))
    np.testing.assert_allclose(view.robot_view.q[columns], response.trajectory.points[-1].positions, atol=1e-6)
    assert view.frames_shown > 2  # played, not jumped to its end
    bad_goal = dict(PAPER_GOAL, r_arm_j4=PAPER_GOAL["r_arm_j4"] + 100.0)
    failed = planning_client.plan(bad_goal, start=PAPER_START, time_budget=1.0)
    assert failed.error.code != PlanningError.SUCCESS
    assert view.status.content.startswith("**")
    assert failed.error.message[:40] in view.status.content


@pytest.fixture(scope="module")
def base_view(rclpy_session):
    """base_view over BARN world 0 (or no world without the dataset), spun in this process."""
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    from maru_planner.physics import barn_world
    from maru_planner.ros.plan_view_bridge import BaseViewNode

    world = 0 if (barn_world.barn_dir() / "grid_files" / "grid_0.npy").is_file() else -1
    overrides = [Parameter("view_port", value=0), Parameter("barn", value=world),
                 Parameter("strip_topic", value="/viewed_base/strip")]  # fmt: skip
    node = BaseViewNode(namespace="viewed_base", parameter_overrides=overrides)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    thread = __import__("threading").Thread(target=executor.spin, daemon=True)
    thread.start()
    yield node
    executor.shutdown(timeout_sec=5.0)
    thread.join(timeout=5.0)
    node.destroy_node()


def test_the_base_run_is_shown_live(base_view, client):
    from nav_msgs.msg import Odometry, Path
    from sensor_msgs.msg import LaserScan

    from maru_planner.ros.reactive_conversions import path_msg

    spinning, _ = client
    assert base_view.settings.barn < 0 or base_view.view.obstacles > 100  # a BARN world's cylinders
    with urllib.request.urlopen(base_view.url, timeout=10.0) as page:
        assert page.status == 200
    node = spinning.node
    odom_pub = node.create_publisher(Odometry, "/viewed_base/odom", 10)
    scan_pub = node.create_publisher(LaserScan, "/viewed_base/scan", 10)
    strip_pub = node.create_publisher(Path, "/viewed_base/strip", 10)
    odom = Odometry()
    odom.pose.pose.position.x, odom.pose.pose.position.y = -2.0, 3.0
    odom.pose.pose.orientation.z, odom.pose.pose.orientation.w = np.sin(0.5), np.cos(0.5)  # yaw 1 rad
    scan = LaserScan(angle_min=0.0, angle_max=0.2, angle_increment=0.1, range_min=0.1, range_max=5.0)
    scan.ranges = [1.0, 1.0, 9.0]  # the last beyond range_max: no point
    strip = path_msg(np.array([[-2.0, 3.0], [-2.0, 4.0], [-1.5, 5.0]]), "odom", 0.0)
    view = base_view.view

    def shown() -> bool:
        for publisher, msg in ((odom_pub, odom), (scan_pub, scan), (strip_pub, strip)):
            publisher.publish(msg)
        return view.pose is not None and len(view.scan_points) == 2 and len(view.strip) == 3

    assert spinning.wait_for(shown, timeout=10.0, period=0.12)
    np.testing.assert_allclose(view.pose, [-2.0, 3.0, 1.0], atol=1e-9)
    laser = base_view.settings.laser_pose
    first = np.array([-2.0, 3.0]) + np.array([np.cos(1.0), np.sin(1.0)]) * (laser[0] + 1.0)  # beam 0 straight ahead
    np.testing.assert_allclose(view.scan_points[0], first, atol=1e-9)  # (laser_pose: x only, yaw 0)
    np.testing.assert_allclose(view.strip[-1], [-1.5, 5.0])
    for publisher in (odom_pub, scan_pub, strip_pub):
        node.destroy_publisher(publisher)
