"""`rbnx replay`: publish a recording on DDS with /clock, so our services run on it as on a live robot.

Reads our MCAP recordings and ROS 2 bags (``.mcap``, ``.db3`` or a rosbag2 directory) with ``rosbags``;
each message's CDR bytes are decoded with our IDL struct of the same ROS 2 type and published on the
(remapped) topic with the QoS its usual writer offers. Timing follows the recording's log times scaled by
``--rate``. Time base: when the recording has /clock (ours do: the sim's clock), /clock is replayed as
recorded; otherwise /clock is published from the log times, so a service with ``use_sim_time`` follows
a real robot's bag. ``--drop-tf CHILD`` removes transforms from /tf, e.g. ``--drop-tf odom`` so a fresh
SLAM is not confused by the recorded run's own map->odom.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

CLOCK = "/clock"


class ReplayError(ValueError):
    """A recording or an argument we cannot replay; str() is one line."""


def parse_remap(arg: str) -> tuple[str, str]:
    """``/scan:=/robot/scan`` -> ('/scan', '/robot/scan')."""
    src, sep, dst = arg.partition(":=")
    if not sep or not src.strip() or not dst.strip():
        raise ReplayError(f"--remap {arg!r}: expected FROM:=TO, e.g. /scan:=/front/scan")
    return "/" + src.strip().lstrip("/"), "/" + dst.strip().lstrip("/")


@dataclass
class ReplayStats:
    published: dict[str, int] = field(default_factory=dict)
    skipped_types: dict[str, str] = field(default_factory=dict)  # topic -> ROS type we have no struct for
    loops: int = 0
    bag_s: float = 0.0

    def summary(self) -> str:
        parts = ", ".join(f"{t} {n}" for t, n in sorted(self.published.items()))
        text = f"{sum(self.published.values())} messages over {self.bag_s:.1f} s of recording: {parts}"
        if self.skipped_types:
            text += "; not replayed (no message type): " + ", ".join(
                f"{t} ({ty})" for t, ty in sorted(self.skipped_types.items()))
        return text


class Replayer:
    """One recording, published on one DDS domain. ``run`` blocks until the end (or ``stop``)."""

    def __init__(self, path: str | Path, *, rate: float = 1.0, loop: bool = False,
                 remaps: dict[str, str] | None = None, topics: list[str] | None = None,
                 drop_tf: list[str] | None = None, clock: bool = True, clock_hz: float = 100.0,
                 delay_s: float = 1.0, domain_id: int | None = None) -> None:
        self.path = Path(path)
        if not self.path.exists():
            raise ReplayError(f"{self.path}: no such file or directory")
        if not self.path.is_dir() and self.path.suffix not in (".mcap", ".db3"):
            raise ReplayError(f"{self.path}: not a recording (.mcap, .db3 or a rosbag2 directory)")
        if not rate > 0:
            raise ReplayError(f"--rate: must be > 0, got {rate}")
        self.rate, self.loop, self.clock, self.delay_s = rate, loop, clock, delay_s
        self.clock_period = 1.0 / clock_hz
        self.remaps = remaps or {}
        self.topics = {"/" + t.lstrip("/") for t in topics} if topics else None
        self.drop_tf = {f.strip().lstrip("/") for f in drop_tf or []}
        self.domain_id = domain_id
        self.stats = ReplayStats()

    def _open(self) -> Any:
        from rosbags.rosbag2 import Reader

        try:
            reader = Reader(self.path)
            reader.open()
        except Exception as exc:
            salvaged = self._salvage()
            if salvaged is None:
                raise ReplayError(f"{self.path}: cannot read: {exc}") from None
            return salvaged
        return reader

    def _salvage(self) -> Any:
        """A recording whose writer was killed has no footer: replay the messages that survived, with a
        one-line warning (None when the file is not such an MCAP, or nothing survived)."""
        if self.path.is_dir() or self.path.suffix != ".mcap":
            return None
        from rbnx.mcap_salvage import SalvageReader

        try:
            reader = SalvageReader(self.path)
        except Exception:  # not MCAP at all (bad magic): the indexed reader's error stands
            return None
        if not reader.truncated or not reader.messages_found:
            return None
        print(f"rbnx replay: warning: {self.path} is truncated (its recorder did not finish it); replaying the "
              f"{reader.messages_found} messages that survived", file=sys.stderr, flush=True)
        return reader

    def run(self, stop: threading.Event | None = None,
            on_progress: Callable[[float, ReplayStats], None] | None = None) -> ReplayStats:
        from robonix_api.dds import Clock, DdsNode, Time

        stop = stop or threading.Event()
        reader = self._open()
        node = DdsNode(domain_id=self.domain_id, name="rbnx_replay")
        try:
            conns, pubs, types = self._publishers(reader, node)
            if not conns:
                raise ReplayError(f"{self.path}: nothing to replay (no topic of a known type selected)")
            recorded_clock = any(c.topic == CLOCK for c in conns)
            clock_pub = None
            if self.clock and not recorded_clock:
                clock_pub = pubs.get(CLOCK) or node.create_publisher(CLOCK, Clock, "best_effort", 10)
            stop.wait(self.delay_s)  # let subscribers discover the writers before the first message
            t_first = reader.start_time
            self.stats.bag_s = (reader.end_time - t_first) * 1e-9
            while not stop.is_set():
                t_wall0, last_clock = time.monotonic(), -1.0
                for conn, ts, raw in reader.messages(connections=conns):
                    rel = (ts - t_first) * 1e-9
                    if not self._sleep_until(t_wall0 + rel / self.rate, stop):
                        break
                    cls, out = types[conn.id]
                    if clock_pub is not None and rel - last_clock >= self.clock_period:
                        clock_pub.publish(Clock(clock=Time(sec=ts // 1_000_000_000, nanosec=ts % 1_000_000_000)))
                        last_clock = rel
                    if not self.clock and conn.topic == CLOCK:
                        continue
                    msg = cls.deserialize(raw)
                    if conn.topic == "/tf" and self.drop_tf:
                        msg.transforms = [t for t in msg.transforms
                                          if t.child_frame_id.strip().lstrip("/") not in self.drop_tf]
                        if not msg.transforms:
                            continue
                    pubs[out].publish(msg)
                    self.stats.published[out] = self.stats.published.get(out, 0) + 1
                    if on_progress is not None:
                        on_progress(rel, self.stats)
                if not self.loop or stop.is_set():
                    break
                self.stats.loops += 1
        finally:
            node.close()
            reader.close()
        return self.stats

    def _publishers(self, reader: Any, node: Any) -> tuple[list[Any], dict[str, Any], dict[int, tuple[Any, str]]]:
        """The recorded connections to replay, one publisher per (remapped) topic, and each connection's
        message class and output topic; connections of unknown types are counted in ``stats.skipped_types``."""
        from rbnx.rosmsg import KNOWN, type_by_name

        conns: list[Any] = []
        pubs: dict[str, Any] = {}
        types: dict[int, tuple[Any, str]] = {}
        for c in reader.connections:
            if self.topics is not None and c.topic not in self.topics:
                continue
            cls = type_by_name(c.msgtype)
            if cls is None:
                self.stats.skipped_types[c.topic] = c.msgtype
                continue
            out = self.remaps.get(c.topic, c.topic)
            if out not in pubs:
                qos = KNOWN[c.topic].qos if c.topic in KNOWN else "reliable"
                pubs[out] = node.create_publisher(out, cls, qos, 1 if qos == "latched" else 100)
            conns.append(c)
            types[c.id] = (cls, out)
        return conns, pubs, types

    @staticmethod
    def _sleep_until(t: float, stop: threading.Event) -> bool:
        dt = t - time.monotonic()
        if dt > 0:
            return not stop.wait(dt)
        return not stop.is_set()
