"""Record a scripted planning session into a rosbag (``rosbags``) and read/replay it.

The session (planning_node in its own process, this process as the robot and
the operator): /joint_states published at 20 Hz, three plans that start from
the latest joint state, one scene change. Recorded: /joint_states, the node's
~/planned_trajectory and ~/markers, each message serialized with
``rclpy.serialization.serialize_message`` and written as raw CDR by the
``rosbags`` writer (``maru_planner.bag``).
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

pytestmark = pytest.mark.ros

NODE = "/planning_node"
JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
START = dict(zip(JOINTS, (-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25), strict=True))
TOPICS = {
    "/joint_states": "sensor_msgs/msg/JointState",
    f"{NODE}/planned_trajectory": "trajectory_msgs/msg/JointTrajectory",
    f"{NODE}/markers": "visualization_msgs/msg/MarkerArray",
}
PLANS = 3


def _state(step: int) -> dict[str, float]:
    """The robot's joint state at publishing step ``step`` (the right elbow creeps)."""
    return dict(START, r_arm_j4=START["r_arm_j4"] + 0.002 * step)


def _message_class(msgtype: str):
    """The rclpy message class of a full type name (``sensor_msgs/msg/JointState``)."""
    import importlib

    package, _, name = msgtype.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


class Recorder:
    """Subscribes to TOPICS and keeps (topic, receive time ns, CDR bytes) in arrival order."""

    def __init__(self, node):
        from rclpy.qos import DurabilityPolicy, QoSProfile
        from rclpy.serialization import serialize_message

        self.records: list[tuple[str, int, bytes]] = []
        self._lock = threading.Lock()
        # Deep queues: a loaded test process may fall behind for a while without losing a message.
        # The trajectory reader is latched like the node's publisher, so a late match loses no plan.
        volatile = QoSProfile(depth=1000)
        latched = QoSProfile(depth=1000, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        for topic, msgtype in TOPICS.items():
            qos = latched if topic.endswith("/planned_trajectory") else volatile
            node.create_subscription(
                _message_class(msgtype), topic, lambda msg, t=topic: self._keep(t, serialize_message(msg)), qos
            )

    def _keep(self, topic: str, raw: bytes) -> None:
        with self._lock:
            self.records.append((topic, time.time_ns(), raw))

    def count(self, topic: str) -> int:
        with self._lock:
            return sum(1 for t, _, _ in self.records if t == topic)

    def write(self, path) -> None:
        from maru_planner.bag.rosbag_io import BagWriter

        with self._lock:
            records = sorted(self.records, key=lambda r: r[1])
        with BagWriter(path) as bag:
            for topic, msgtype in TOPICS.items():
                bag.add_topic(topic, msgtype)
            for topic, stamp_ns, raw in records:
                bag.write(topic, stamp_ns, raw)


@pytest.fixture(scope="module")
def session_bag(node_process, rclpy_session, tmp_path_factory):
    """Run the scripted session once; returns (bag path, the plan responses, last published state)."""
    from conftest import SpinningNode, wait_until_node_has_joint_states

    from maru_planner.paths import config_path
    from maru_planner.ros.planning_client import PlanningClient
    from maru_planner.ros.planning_conversions import joint_state_msg
    from maru_planner_interfaces.msg import PlanningError

    proc = node_process(
        "maru_planner.ros.planning_node", ["--ros-args", "--params-file", str(config_path("planner.yaml"))]
    )
    spinning = SpinningNode("bag_session")
    node = spinning.node
    recorder = Recorder(node)
    client = PlanningClient(node=node)
    assert client.plan_client.wait_for_service(timeout_sec=120.0), proc.log()
    client.wait_until_ready(timeout=120.0)  # the node has matched our service clients too
    from sensor_msgs.msg import JointState

    publisher = node.create_publisher(JointState, "/joint_states", 10)
    assert spinning.wait_for(lambda: publisher.get_subscription_count() >= 2, 60.0)  # the node and the recorder
    # the node's marker timer greets the recorder's new subscription with the scene (so it has matched it)
    assert spinning.wait_for(lambda: recorder.count(f"{NODE}/markers") >= 1, timeout=60.0)
    stop = threading.Event()
    published: list[dict[str, float]] = []

    def robot():
        step = 0
        while not stop.is_set():
            state = _state(step)
            publisher.publish(joint_state_msg(list(state), list(state.values()), node.get_clock().now().to_msg()))
            published.append(state)
            step += 1
            time.sleep(0.05)

    thread = threading.Thread(target=robot, daemon=True)
    thread.start()
    responses = []
    try:
        assert spinning.wait_for(lambda: recorder.count("/joint_states") >= 5)
        wait_until_node_has_joint_states(client)
        for i in range(PLANS):
            if i == 1:
                pose = np.eye(4)
                pose[:3, 3] = [-1.0, 0.5, 0.0]
                answer = client.add_obstacle("behind_robot", "box", [0.2, 0.2, 0.2], pose)
                assert answer.error.code == PlanningError.SUCCESS, answer.error.message
            goal = dict(START, r_arm_j4=START["r_arm_j4"] + 0.3 + 0.1 * i)
            response = client.plan(goal, start=None, planner_id="RRTConnect", time_budget=5.0, seed=i)
            assert response.error.code == PlanningError.SUCCESS, response.error.message
            responses.append(response)
        # markers: the greeting, one per plan (sent after its answer), one for the scene change
        for topic, expected in ((f"{NODE}/planned_trajectory", PLANS), (f"{NODE}/markers", PLANS + 2)):
            arrived = spinning.wait_for(lambda t=topic, n=expected: recorder.count(t) >= n, timeout=60.0)
            assert arrived, f"{topic}: {recorder.count(topic)} messages, expected {expected}"
    finally:
        stop.set()
        thread.join(timeout=2.0)
    path = tmp_path_factory.mktemp("bags") / "planning_session"
    recorder.write(path)
    yield path, responses, published, spinning, client, publisher
    spinning.destroy()


def test_session_bag_holds_every_topic(session_bag):
    from maru_planner.bag.rosbag_io import summarize

    path, responses, published, _, _, _ = session_bag
    summary = summarize(path)
    assert summary.topics == TOPICS
    assert summary.counts[f"{NODE}/planned_trajectory"] == len(responses) == PLANS
    assert summary.counts[f"{NODE}/markers"] >= PLANS + 2  # the greeting, one per plan, one per scene change
    assert 5 <= summary.counts["/joint_states"] <= len(published)


def test_replay_reads_back_types_counts_and_increasing_timestamps(session_bag):
    from rclpy.serialization import deserialize_message

    from maru_planner.bag.rosbag_io import read_messages

    path, responses, _, _, _, _ = session_bag
    by_topic: dict[str, list] = {topic: [] for topic in TOPICS}
    for record in read_messages(path):
        assert record.msgtype == TOPICS[record.topic]
        by_topic[record.topic].append(
            (record.timestamp_ns, deserialize_message(record.rawdata, _message_class(record.msgtype)))
        )
    for topic, items in by_topic.items():
        stamps = [t for t, _ in items]
        assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps), topic
    header_stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in by_topic["/joint_states"]]
    assert all(b > a for a, b in zip(header_stamps, header_stamps[1:]))
    trajectories = [m for _, m in by_topic[f"{NODE}/planned_trajectory"]]
    for recorded, response in zip(trajectories, responses, strict=True):
        assert list(recorded.joint_names) == JOINTS
        assert len(recorded.points) == len(response.trajectory.points)
        np.testing.assert_allclose(recorded.points[-1].positions, response.trajectory.points[-1].positions)
    # every plan started from a /joint_states message the robot had published before it
    recorded_states = [tuple(m.position) for _, m in by_topic["/joint_states"]]
    for recorded in trajectories:
        start = dict(zip(recorded.joint_names, recorded.points[0].positions, strict=True))
        assert any(np.allclose([start[n] for n in JOINTS], s) for s in recorded_states)
    namespaces = {mk.ns for _, m in by_topic[f"{NODE}/markers"] for mk in m.markers}
    assert {"scene", "hand_path"} <= namespaces
    scene_texts = {mk.text for _, m in by_topic[f"{NODE}/markers"] for mk in m.markers if mk.ns == "scene"}
    assert "behind_robot" in scene_texts


def test_replayed_joint_states_drive_the_next_plan(session_bag):
    """Publish the bag's /joint_states back as raw CDR; the node plans from the last one."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState

    from maru_planner.bag.rosbag_io import read_messages
    from maru_planner_interfaces.msg import PlanningError

    # the session's publisher: the node has matched it (the session's plans started from its messages)
    path, _, _, _, client, publisher = session_bag
    records = list(read_messages(path, ["/joint_states"]))[:10]
    for record in records:
        publisher.publish(record.rawdata)  # the recorded bytes, as `ros2 bag play` would send them
        time.sleep(0.02)
    last = deserialize_message(records[-1].rawdata, JointState)
    expected = dict(zip(last.name, last.position, strict=True))
    goal = dict(START, r_arm_j4=START["r_arm_j4"] + 0.45)

    def first_point(response) -> dict[str, float]:
        return dict(zip(response.trajectory.joint_names, response.trajectory.points[0].positions, strict=True))

    def plan_started_at_last(response) -> bool:
        if response.error.code != PlanningError.SUCCESS:
            return False
        first = first_point(response)
        return bool(np.allclose([first[n] for n in JOINTS], [expected[n] for n in JOINTS], atol=1e-9))

    # the messages are on their way, nothing orders them with the plan request: plan until they are in
    deadline = time.monotonic() + 60.0
    response = client.plan(goal, start=None, planner_id="RRTConnect", time_budget=5.0, seed=11)
    while not plan_started_at_last(response) and time.monotonic() < deadline:
        time.sleep(0.1)
        response = client.plan(goal, start=None, planner_id="RRTConnect", time_budget=5.0, seed=11)
    assert response.error.code == PlanningError.SUCCESS, response.error.message
    first = first_point(response)
    np.testing.assert_allclose([first[n] for n in JOINTS], [expected[n] for n in JOINTS], atol=1e-9)
