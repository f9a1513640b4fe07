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


def qos_metadata(qos: str) -> str:
    rel = 2 if qos == "best_effort" else 1
    dur = 1 if qos == "latched" else 2
    return _QOS_YAML.format(depth=1 if qos == "latched" else 10, rel=rel, dur=dur)


class McapRecorder:
    """Subscribes to ``specs`` on a DDS domain and appends every sample to an MCAP file.

    The samples come from a :class:`rbnx.ddstap.RawTap`: the wire bytes as received, each stamped with its
    receive time, written as they are. The tap's one thread writes, so writes never interleave; every
    ``flush_s`` it closes the chunk in progress and flushes it to the file. ``stop`` ends the thread before
    finishing the file.
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
        self._tap: Any = None
        self._channels: list[int] = []  # MCAP channel id per spec index
        self._dirty = False
        self._lock = threading.RLock()  # re-entered by before_finish hooks that read the counts
        self._closed = False

    def start(self) -> None:
        from mcap.writer import Writer

        from rbnx.ddstap import RawTap
        from rbnx.rosmsg import ros_name, schema_text

        if isinstance(self.output, str | Path):
            self._fh = open(self.output, "wb")  # noqa: SIM115 - kept open until stop()
            out: Any = self._fh
        else:
            out = self.output
        self._writer = Writer(out)
        self._writer.start(profile="ros2", library="robonix-nav rbnx record")
        self._writer.flush()  # the header reaches the disk before the first message
        schemas: dict[type, int] = {}
        for s in self.specs:
            if s.msg_type not in schemas:
                schemas[s.msg_type] = self._writer.register_schema(
                    name=ros_name(s.msg_type), encoding="ros2msg", data=schema_text(s.msg_type).encode())
            self._channels.append(self._writer.register_channel(
                topic=s.topic, message_encoding="cdr", schema_id=schemas[s.msg_type],
                metadata={"offered_qos_profiles": qos_metadata(s.qos)}))
        self._tap = RawTap(self.specs, self._on_sample, domain_id=self.domain_id, name="rbnx_record",
                           tick_s=self.flush_s, on_tick=self._flush)
        self._tap.start()

    def _on_sample(self, index: int, data: bytes, recv_ns: int, _writer: int) -> None:
        with self._lock:
            self._write(self._channels[index], self.specs[index].topic, recv_ns, data)
            self._dirty = True

    def _flush(self) -> None:
        """Close the chunk in progress and write it out (a SIGKILL loses at most ``flush_s``)."""
        if not self._dirty:
            return
        with self._lock:
            self._writer.flush()
            self.flushes += 1
            self._dirty = False
        self.flushed()

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
        tap, self._tap = self._tap, None
        if tap is not None:
            tap.stop()
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


def spec_from_publication(pub: Any) -> TopicSpec | None:
    """The TopicSpec a DDS publication (builtin DCPSPublication sample) offers: its ROS 2 topic, our class for
    its type and its QoS preset; None for a non-ROS topic or a type we have no class for."""
    from cyclonedds.qos import Policy

    from rbnx.rosmsg import TopicSpec, type_by_name

    name = getattr(pub, "topic_name", None) or ""  # None in the sample of a writer that went away
    if not name.startswith("rt/") or not getattr(pub, "type_name", None):
        return None
    pkg, _, rest = pub.type_name.partition("::msg::dds_::")
    cls = type_by_name(f"{pkg}/msg/{rest.rstrip('_')}") if rest else None
    if cls is None:
        return None
    best_effort = pub.qos[Policy.Reliability] == Policy.Reliability.BestEffort
    latched = pub.qos[Policy.Durability] == Policy.Durability.TransientLocal
    return TopicSpec(name[2:], cls, "best_effort" if best_effort else "latched" if latched else "reliable")


def discover_topics(names: list[str], domain_id: int | None, timeout_s: float) -> list[TopicSpec]:
    """Type and QoS of topics we have no entry for, from DDS discovery (the writers' publication data):
    what `ros2 bag record` does too. TopicError naming the topic when no writer shows up in time."""
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication

    from rbnx.rosmsg import TopicError
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
                spec = spec_from_publication(pub)
                if spec is None:
                    raise TopicError(f"topic {name}: its type {pub.type_name} is not one we can record")
                found[name] = spec
            time.sleep(0.05)
        reader.__del__()
    missing = [n for n in names if n not in found]
    if missing:
        raise TopicError(f"topic {missing[0]}: no writer seen in {timeout_s:g} s to learn its type; "
                         f"give it as {missing[0]}:pkg/Type")
    return [found[n] for n in names]
