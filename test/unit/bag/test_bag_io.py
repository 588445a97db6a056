"""rosbag2 helpers: write/read round trips in sqlite3 and mcap, typed decoding, rclpy CDR compatibility, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.bag import (
    TF_MSGTYPE,
    BagError,
    BagWriter,
    planar_pose_of,
    planar_transform,
    read_messages,
    summarize,
    tf_message,
    typestore,
)

SCAN = "sensor_msgs/msg/LaserScan"


def _typestore_scan(stamp_ns: int, ranges):
    types = typestore().types
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9), frame_id="laser"
    )
    return types[SCAN](
        header=header,
        angle_min=-math.pi / 2,
        angle_max=math.pi / 2,
        angle_increment=math.pi / (len(ranges) - 1),
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.1,
        range_max=10.0,
        ranges=np.asarray(ranges, dtype=np.float32),
        intensities=np.zeros(0, dtype=np.float32),
    )


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_typestore_messages_round_trip_in_timestamp_order(tmp_path, storage):
    path = tmp_path / "bag"
    with BagWriter(path, storage=storage) as bag:
        bag.add_topic("/scan", SCAN)
        bag.add_topic("/tf", TF_MSGTYPE)
        for k in range(5):
            stamp = 1_000_000_000 + k * 100_000_000
            bag.write("/tf", stamp, tf_message([planar_transform("odom", "base_link", stamp, 0.1 * k, -0.2, 0.3 * k)]))
            bag.write("/scan", stamp + 1, _typestore_scan(stamp, [1.0 + k, 2.0, float("inf")]))

    summary = summarize(path)
    assert summary.storage == storage
    assert summary.topics == {"/scan": SCAN, "/tf": TF_MSGTYPE}
    assert summary.counts == {"/scan": 5, "/tf": 5}
    assert summary.duration_s == pytest.approx(0.4, abs=1e-6)

    records = list(read_messages(path))
    assert [r.timestamp_ns for r in records] == sorted(r.timestamp_ns for r in records)
    scans = [r.decode() for r in records if r.topic == "/scan"]
    assert [float(s.ranges[0]) for s in scans] == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert math.isinf(scans[0].ranges[2]) and scans[0].header.frame_id == "laser"
    poses = [planar_pose_of(r.decode().transforms[0]) for r in records if r.topic == "/tf"]
    assert poses[3] == pytest.approx((0.3, -0.2, 0.9))


def test_topic_filter_reads_only_those_topics(tmp_path):
    path = tmp_path / "bag"
    with BagWriter(path) as bag:
        bag.add_topic("/scan", SCAN)
        bag.add_topic("/tf", TF_MSGTYPE)
        bag.write("/scan", 5, _typestore_scan(5, [1.0, 2.0]))
        bag.write("/tf", 6, tf_message([]))
    assert [r.topic for r in read_messages(path, topics=["/tf"])] == ["/tf"]
    assert list(read_messages(path, topics=["/nothing"])) == []


def test_rclpy_serialized_bytes_are_stored_verbatim_and_decode_both_ways(tmp_path):
    from rclpy.serialization import deserialize_message, serialize_message
    from sensor_msgs.msg import LaserScan

    msg = LaserScan()
    msg.header.frame_id = "laser"
    msg.angle_increment = 0.5
    msg.ranges = [0.5, 1.5, float("nan")]
    raw = serialize_message(msg)
    path = tmp_path / "bag"
    with BagWriter(path, storage="mcap") as bag:
        bag.add_topic("/scan", SCAN)
        bag.write("/scan", 42, raw)
    (record,) = read_messages(path)
    assert record.rawdata == raw and record.timestamp_ns == 42
    assert list(record.decode().ranges[:2]) == [0.5, 1.5]
    back = deserialize_message(record.rawdata, LaserScan)
    assert back.header.frame_id == "laser" and math.isnan(back.ranges[2])


def test_writer_and_reader_errors_name_the_problem(tmp_path):
    with pytest.raises(BagError, match="unknown bag storage"):
        BagWriter(tmp_path / "a", storage="rosbag1")
    with BagWriter(tmp_path / "b") as bag:
        with pytest.raises(BagError, match="unknown message type"):
            bag.add_topic("/x", "sensor_msgs/LaserScan")
        bag.add_topic("/scan", SCAN)
        with pytest.raises(BagError, match="already declared"):
            bag.add_topic("/scan", TF_MSGTYPE)
        with pytest.raises(BagError, match="not declared"):
            bag.write("/tf", 1, b"\x00")
        with pytest.raises(BagError, match="carries sensor_msgs/msg/LaserScan"):
            bag.write("/scan", 1, tf_message([]))
        with pytest.raises(BagError, match="negative timestamp"):
            bag.write("/scan", -1, b"\x00")
    with pytest.raises(BagError, match="exists already"):
        BagWriter(tmp_path / "b")
    with pytest.raises(BagError, match="not a rosbag2 directory"):
        list(read_messages(tmp_path / "missing"))
