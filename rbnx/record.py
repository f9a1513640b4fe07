"""`rbnx record`: write DDS topics to an MCAP file that Foxglove and ``ros2 bag`` open.

Each channel carries ROS 2 CDR (XCDR1 little-endian with its 4-byte encapsulation header, the bytes
rmw_cyclonedds puts on the wire) and a ``ros2msg`` schema generated from the same IDL struct, so a reader
needs no ROS install and no knowledge of this project. Log and publish times are the receive time (wall
clock, ns, taken per message as it is read off the reader, as rosbag2 stamps each callback); the messages keep
their own header stamps (sim time under ``use_sim_time``), and /clock is recorded as a topic, which is what
replay uses as its time base.

The file survives a crash: the chunk in progress is closed and written out every ``flush_s`` (0.5 s), so a
SIGKILL loses at most that much. Such a file has no summary or footer; mcap's ``NonSeekingReader``
(``rbnx.record.read_truncated``) and ``rbnx replay`` read it up to the last whole record. ``--format rosbag2``
(:mod:`rbnx.rosbag2_out`) writes the same file inside a rosbag2 folder with its ``metadata.yaml``.
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rbnx.rosmsg import TopicSpec

# rbnx.rosmsg (and with it cyclonedds) is imported where it is used, so `rbnx --help` stays fast.
DEFAULT_TOPIC_NAMES = "/scan /odom /tf /tf_static /map /plan /cmd_vel /clock"

# rosbag2's offered_qos_profiles metadata (rmw enum values: reliability 1 reliable / 2 best effort,
# durability 1 transient local / 2 volatile, history 1 keep last), so `ros2 bag play` re-offers them.
_QOS_YAML = ("- history: 1\n  depth: {depth}\n  reliability: {rel}\n  durability: {dur}\n"
             "  deadline:\n    sec: 9223372036\n    nsec: 854775807\n"
             "  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n"
             "  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n"
             "  avoid_ros_namespace_conventions: false\n")

FLUSH_S = 0.5  # seconds between chunk flushes: what a SIGKILL may lose at most
WAIT_S = 0.2  # longest wait for data, so stop() and the flush timer are noticed


def qos_metadata(qos: str) -> str:
    rel = 2 if qos == "best_effort" else 1
    dur = 1 if qos == "latched" else 2
    return _QOS_YAML.format(depth=1 if qos == "latched" else 10, rel=rel, dur=dur)


class McapRecorder:
    """Subscribes to ``specs`` on a DDS domain and appends every sample to an MCAP file.

    Samples are taken as the serialized bytes Cyclone received (``ddspy_take``, the call under
    cyclonedds' ``DataReader.take``, pinned with cyclonedds) and written as they are: no decode and
    re-encode, so the file holds the wire bytes and recording stays cheap. One thread waits on all
    readers and writes, so writes never interleave; ``stop`` ends it before finishing the file.
    Every sample gets the wall-clock time of the take that read it as log time: the thread wakes as soon as
    data arrives (no batching), so consecutive messages get distinct receive times.
    """

    def __init__(self, output: str | Path | IO[bytes], specs: list[TopicSpec] | tuple[TopicSpec, ...],
                 domain_id: int | None = None, flush_s: float = FLUSH_S) -> None:
        self.output = output
        self.specs = list(specs)
        self.domain_id = domain_id
        self.flush_s = flush_s
        self.counts: dict[str, int] = {s.topic: 0 for s in self.specs}
        self.bytes = 0
        self.first_ns: int | None = None  # log time of the first and last message written
        self.last_ns: int | None = None
        self.flushes = 0
        self._writer: Any = None
        self._fh: IO[bytes] | None = None
        self._node: Any = None
        self._readers: list[tuple[Any, int, str]] = []  # (DataReader, channel id, topic)
        self._conds: list[Any] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.RLock()  # re-entered by before_finish hooks that read the counts
        self._closed = False

    def start(self) -> None:
        from cyclonedds.core import (
            GuardCondition,
            InstanceState,
            ReadCondition,
            SampleState,
            ViewState,
            WaitSet,
        )
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        from mcap.writer import Writer

        from rbnx.rosmsg import ros_name, schema_text
        from robonix_api.dds import DdsNode, dds_topic_name
        from robonix_api.dds.qos import resolve_qos

        if isinstance(self.output, str | Path):
            self._fh = open(self.output, "wb")  # noqa: SIM115 - kept open until stop()
            out: Any = self._fh
        else:
            out = self.output
        self._writer = Writer(out)
        self._writer.start(profile="ros2", library="robonix-nav rbnx record")
        self._writer.flush()  # the header reaches the disk before the first message
        schemas: dict[type, int] = {}
        self._node = node = DdsNode(domain_id=self.domain_id, name="rbnx_record")
        self._waitset = WaitSet(node.participant)
        self._guard = GuardCondition(node.participant)
        self._waitset.attach(self._guard)
        mask = SampleState.NotRead | ViewState.Any | InstanceState.Any
        for s in self.specs:
            if s.msg_type not in schemas:
                schemas[s.msg_type] = self._writer.register_schema(
                    name=ros_name(s.msg_type), encoding="ros2msg", data=schema_text(s.msg_type).encode())
            channel = self._writer.register_channel(
                topic=s.topic, message_encoding="cdr", schema_id=schemas[s.msg_type],
                metadata={"offered_qos_profiles": qos_metadata(s.qos)})
            topic = Topic(node.participant, dds_topic_name(s.topic), s.msg_type)
            reader = DataReader(node.participant, topic, resolve_qos(s.qos, 1 if s.qos == "latched" else 200))
            cond = ReadCondition(reader, mask)
            self._waitset.attach(cond)
            self._conds.append(cond)
            self._readers.append((reader, channel, s.topic))
        self._thread = threading.Thread(target=self._run, name="rbnx-record", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from cyclonedds._clayer import ddspy_take
        from cyclonedds.core import InstanceState, SampleState, ViewState
        from cyclonedds.util import duration

        mask = SampleState.Any | ViewState.Any | InstanceState.Any
        next_flush = time.monotonic() + self.flush_s
        dirty = False
        while not self._stop.is_set():
            wait_s = max(0.001, min(WAIT_S, next_flush - time.monotonic()))
            self._waitset.wait(duration(seconds=wait_s))
            for reader, channel, topic in self._readers:
                while True:
                    got = ddspy_take(reader._ref, mask, 64)
                    if isinstance(got, int) or not got:
                        break
                    now = time.time_ns()
                    with self._lock:
                        for data, info in got:
                            if info.valid_data:
                                self._write(channel, topic, now, data)
                                dirty = True
            if time.monotonic() >= next_flush:
                next_flush = time.monotonic() + self.flush_s
                if dirty:
                    with self._lock:
                        self._writer.flush()
                        self.flushes += 1
                    self.flushed()
                    dirty = False

    def _write(self, channel: int, topic: str, log_ns: int, data: bytes) -> None:
        """One message (caller holds the lock); log times never go backwards within the file."""
        if self.last_ns is not None and log_ns < self.last_ns:
            log_ns = self.last_ns
        self._writer.add_message(channel_id=channel, log_time=log_ns, publish_time=log_ns, data=data,
                                 sequence=self.counts[topic])
        self.counts[topic] += 1
        self.bytes += len(data)
        if self.first_ns is None:
            self.first_ns = log_ns
        self.last_ns = log_ns

    def flushed(self) -> None:
        """Called after each periodic flush (outside the lock); the rosbag2 layout rewrites its metadata."""

    def before_finish(self, writer: Any) -> None:
        """Called with the writer just before its summary is written (the rosbag2 layout adds a record)."""

    def stop(self) -> None:
        """End the reading thread, close the DDS entities, then finish the file. Idempotent."""
        self._stop.set()
        if self._thread is not None:
            self._guard.set(True)
            self._thread.join(10.0)
            self._thread = None
        node, self._node = self._node, None
        if node is not None:  # delete our entities now (as DdsNode does for its own), then the participant
            for ent in [*self._conds, *(r for r, _, _ in self._readers), self._guard, self._waitset]:
                ent.__del__()
            self._conds.clear()
            self._readers.clear()
            node.close()
        with self._lock:
            if self._closed:
                return
            self._closed = True
            if self._writer is not None:
                self.before_finish(self._writer)
                self._writer.finish()
            if self._fh is not None:
                self._fh.close()

    def duration_s(self) -> float:
        """Seconds between the first and the last message's log time (0 before two messages)."""
        with self._lock:
            return 0.0 if self.first_ns is None or self.last_ns is None else (self.last_ns - self.first_ns) / 1e9

    def summary(self) -> str:
        with self._lock:
            parts = ", ".join(f"{t} {n}" for t, n in self.counts.items())
            return f"{sum(self.counts.values())} messages ({self.bytes / 1e6:.1f} MB): {parts}"


def read_truncated(path: str | Path) -> Iterator[tuple[Any, Any, Any]]:
    """(schema, channel, message) of every whole message in an MCAP file, in file order, also when the
    file was cut short (a recorder killed before it wrote the summary): reading stops at the first
    incomplete record instead of raising."""
    from mcap.exceptions import McapError
    from mcap.reader import NonSeekingReader

    with open(path, "rb") as f:
        it = NonSeekingReader(f).iter_messages(log_time_order=False)
        while True:
            try:
                item = next(it)
            except StopIteration:
                return
            except (McapError, EOFError, ValueError, struct.error):
                return
            yield item


def discover_topics(names: list[str], domain_id: int | None, timeout_s: float) -> list[TopicSpec]:
    """Type and QoS of topics we have no entry for, from DDS discovery (the writers' publication data):
    what `ros2 bag record` does too. TopicError naming the topic when no writer shows up in time."""
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication
    from cyclonedds.qos import Policy

    from rbnx.rosmsg import TopicError, TopicSpec, type_by_name
    from robonix_api.dds import DdsNode, dds_topic_name

    wanted = {dds_topic_name(n): n for n in names}
    found: dict[str, TopicSpec] = {}
    with DdsNode(domain_id=domain_id, name="rbnx_record_discovery") as node:
        reader = BuiltinDataReader(node.participant, BuiltinTopicDcpsPublication)
        deadline = time.monotonic() + timeout_s
        while len(found) < len(wanted) and time.monotonic() < deadline:
            for pub in reader.take(N=256):
                name = wanted.get(getattr(pub, "topic_name", ""))
                if name is None or name in found:
                    continue
                pkg, _, rest = pub.type_name.partition("::msg::dds_::")
                cls = type_by_name(f"{pkg}/msg/{rest.rstrip('_')}")
                if cls is None:
                    raise TopicError(f"topic {name}: its type {pub.type_name} is not one we can record")
                best_effort = pub.qos[Policy.Reliability] == Policy.Reliability.BestEffort
                latched = pub.qos[Policy.Durability] == Policy.Durability.TransientLocal
                found[name] = TopicSpec(name, cls, "best_effort" if best_effort else
                                        "latched" if latched else "reliable")
            time.sleep(0.05)
        reader.__del__()
    missing = [n for n in names if n not in found]
    if missing:
        raise TopicError(f"topic {missing[0]}: no writer seen in {timeout_s:g} s to learn its type; "
                         f"give it as {missing[0]}:pkg/Type")
    return [found[n] for n in names]
