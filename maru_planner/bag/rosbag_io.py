"""Write and read rosbag2 bags (sqlite3 or mcap) with the pure-Python ``rosbags`` library.

No rclpy here: a message is written either as CDR bytes that someone else
serialized (``rclpy.serialization.serialize_message`` gives exactly the bytes
a ``ros2 bag record`` would store) or as a ``rosbags`` typestore message, which
this module serializes. Reading gives :class:`BagMessage` records that keep the
raw CDR (for replay through rclpy) and decode lazily to typestore messages.

Message types are full ROS 2 names (``sensor_msgs/msg/LaserScan``); their
definitions come from the ROS 2 Jazzy typestore, so a bag written here opens
in ``ros2 bag info`` / ``ros2 bag play`` on a full install.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

from rosbags.interfaces import Connection
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.rosbag2.errors import ReaderError, WriterError
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from maru_planner.errors import MaruError

STORAGE_PLUGINS = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}


class BagError(MaruError, ValueError):
    """A bag cannot be written or read as asked (names the bag and what is wrong)."""

    source = "bag"


@cache
def typestore() -> Typestore:
    """The ROS 2 Jazzy message typestore shared by writers and readers."""
    return get_typestore(Stores.ROS2_JAZZY)


def _check_msgtype(msgtype: str) -> None:
    if msgtype not in typestore().fielddefs:
        raise BagError(f"unknown message type {msgtype!r} (expected e.g. 'sensor_msgs/msg/LaserScan')")


@dataclass(frozen=True)
class BagMessage:
    """One recorded message: topic, type, receive timestamp (ns) and its CDR bytes."""

    topic: str
    msgtype: str
    timestamp_ns: int
    rawdata: bytes

    def decode(self) -> object:
        """The message as a ``rosbags`` typestore dataclass (fields as in the .msg file)."""
        return typestore().deserialize_cdr(self.rawdata, self.msgtype)


@dataclass
class BagSummary:
    """What a bag holds: per topic its type and message count, and the time span.

    A topic's type is None where its connections carry different types.
    """

    path: Path
    storage: str
    topics: dict[str, str | None] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    start_ns: int = 0
    end_ns: int = 0

    @property
    def duration_s(self) -> float:
        return max(0, self.end_ns - self.start_ns) / 1e9


class BagWriter:
    """Write a new rosbag2 bag; use as a context manager.

    >>> with BagWriter("out_bag", storage="mcap") as bag:
    ...     bag.add_topic("/scan", "sensor_msgs/msg/LaserScan")
    ...     bag.write("/scan", stamp_ns, cdr_bytes)
    """

    def __init__(self, path: str | Path, storage: str = "sqlite3") -> None:
        if storage not in STORAGE_PLUGINS:
            raise BagError(f"unknown bag storage {storage!r}; use one of {sorted(STORAGE_PLUGINS)}")
        self.path = Path(path)
        self.storage = storage
        try:
            self._writer = Writer(self.path, version=Writer.VERSION_LATEST, storage_plugin=STORAGE_PLUGINS[storage])
        except WriterError as exc:
            raise BagError(f"cannot create bag {self.path}: {exc}") from exc
        self._connections: dict[str, Connection] = {}
        self._msgtypes: dict[str, str] = {}
        self._open = False

    def open(self) -> BagWriter:
        self._writer.open()
        self._open = True
        return self

    def close(self) -> None:
        if self._open:
            self._writer.close()
            self._open = False

    def __enter__(self) -> BagWriter:
        return self.open()

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def add_topic(self, topic: str, msgtype: str) -> None:
        """Declare a topic and its message type (once per topic)."""
        if not self._open:
            raise BagError(f"bag {self.path} is not open")
        _check_msgtype(msgtype)
        if topic in self._connections:
            if self._msgtypes[topic] != msgtype:
                raise BagError(f"topic {topic} already declared as {self._msgtypes[topic]}, not {msgtype}")
            return
        self._connections[topic] = self._writer.add_connection(topic, msgtype, typestore=typestore())
        self._msgtypes[topic] = msgtype

    def write(self, topic: str, timestamp_ns: int, message: object) -> None:
        """Append one message: CDR ``bytes`` or a typestore message of the topic's type."""
        if topic not in self._connections:
            raise BagError(f"topic {topic} was not declared with add_topic()")
        if timestamp_ns < 0:
            raise BagError(f"negative timestamp {timestamp_ns} on {topic}")
        data: bytes | memoryview
        if isinstance(message, bytes | bytearray | memoryview):
            data = bytes(message)
        else:
            expected = self._msgtypes[topic]
            if getattr(message, "__msgtype__", None) != expected:
                raise BagError(f"{topic} carries {expected}, got {type(message).__name__}")
            data = typestore().serialize_cdr(message, expected)
        self._writer.write(self._connections[topic], int(timestamp_ns), data)


def _open_reader(path: str | Path) -> Reader:
    path = Path(path)
    if not (path / "metadata.yaml").is_file():
        raise BagError(f"{path} is not a rosbag2 directory (no metadata.yaml)")
    try:
        reader = Reader(path)
        reader.open()
    except ReaderError as exc:
        raise BagError(f"cannot read bag {path}: {exc}") from exc
    return reader


def read_messages(path: str | Path, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
    """Yield the bag's messages in timestamp order, optionally only some topics."""
    reader = _open_reader(path)
    try:
        wanted = set(topics) if topics is not None else None
        connections = [c for c in reader.connections if wanted is None or c.topic in wanted]
        if wanted is not None and not connections:
            return
        for connection, timestamp, rawdata in reader.messages(connections=connections):
            yield BagMessage(connection.topic, connection.msgtype, int(timestamp), bytes(rawdata))
    finally:
        reader.close()


def summarize(path: str | Path) -> BagSummary:
    """Topics, types, counts and time span of a bag, without decoding messages."""
    reader = _open_reader(path)
    try:
        storage = "mcap" if any(Path(path).glob("*.mcap")) else "sqlite3"
        summary = BagSummary(Path(path), storage)
        for topic, info in reader.topics.items():
            summary.topics[topic] = info.msgtype
            summary.counts[topic] = info.msgcount
        if reader.message_count:
            summary.start_ns, summary.end_ns = reader.start_time, reader.end_time
        return summary
    finally:
        reader.close()
