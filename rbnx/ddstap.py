"""Raw DDS taps: the serialized bytes of every sample on a set of topics, each with its receive time.

What `rbnx record` and the live Foxglove bridge share. Samples are taken as the serialized bytes Cyclone
received (``ddspy_take``, the call under cyclonedds' ``DataReader.take``, pinned with cyclonedds): no decode
and re-encode, so consumers get the wire bytes (ROS 2 CDR with its encapsulation header) cheaply. One
thread waits on all readers and wakes as soon as data arrives (no batching), so each take is stamped with
the wall-clock time it was read: consecutive messages get distinct receive times, as rosbag2 stamps each
callback. Readers may be added while running (topics found by discovery); ``tick`` runs every ``tick_s``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rbnx.rosmsg import TopicSpec

log = logging.getLogger(__name__)

WAIT_S = 0.2  # longest wait for data, so stop() and the tick are noticed

#: on_sample(spec index, CDR bytes, receive time ns, publication handle of the writer)
SampleFn = Callable[[int, bytes, int, int], None]


class RawTap:
    """Readers for ``specs`` on one participant and the thread that hands their samples to ``on_sample``."""

    def __init__(self, specs: list[TopicSpec], on_sample: SampleFn, *, domain_id: int | None = None,
                 name: str = "rbnx_tap", tick_s: float = 0.5, on_tick: Callable[[], None] | None = None) -> None:
        self.specs: list[TopicSpec] = []
        self.on_sample = on_sample
        self.domain_id = domain_id
        self.name = name
        self.tick_s = tick_s
        self.on_tick = on_tick
        self.node: Any = None
        self._readers: list[Any] = []
        self._conds: list[Any] = []
        self._owned: list[Any] = []  # other entities on our participant, deleted with it
        self._pending: list[TopicSpec] = list(specs)
        self._add_lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Create the participant and the readers (so writers see them when this returns), then the thread."""
        from cyclonedds.core import GuardCondition, WaitSet

        from robonix_api.dds import DdsNode

        self.node = DdsNode(domain_id=self.domain_id, name=self.name)
        self._waitset = WaitSet(self.node.participant)
        self._guard = GuardCondition(self.node.participant)
        self._waitset.attach(self._guard)
        self._attach_pending()
        self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
        self._thread.start()

    def own(self, entity: Any) -> Any:
        """Delete ``entity`` (e.g. a builtin-topic reader on :attr:`node`) in :meth:`stop`, before the participant."""
        self._owned.append(entity)
        return entity

    def add(self, spec: TopicSpec) -> int:
        """Subscribe to one more topic (any thread); returns its index. Its reader exists when the tap's
        thread next wakes (at once: the guard condition wakes it)."""
        with self._add_lock:
            self._pending.append(spec)
            index = len(self.specs) + len(self._pending) - 1
        if self._thread is not None:
            self._guard.set(True)
        return index

    def _attach_pending(self) -> None:
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from robonix_api.dds import dds_topic_name
        from robonix_api.dds.qos import resolve_qos

        with self._add_lock:
            pending, self._pending = self._pending, []
        mask = SampleState.NotRead | ViewState.Any | InstanceState.Any
        for s in pending:
            topic = Topic(self.node.participant, dds_topic_name(s.topic), s.msg_type)
            reader = DataReader(self.node.participant, topic,
                                resolve_qos(s.qos, 1 if s.qos == "latched" else 200))
            cond = ReadCondition(reader, mask)
            self._waitset.attach(cond)
            self._conds.append(cond)
            self._readers.append(reader)
            self.specs.append(s)
        if pending:
            self.node.announce(*self._readers[-len(pending):])  # on ros_discovery_info, as /<name>

    def _run(self) -> None:
        """The loop, kept alive through a failing consumer callback (logged): a tap must not go silent."""
        while not self._stop.is_set():
            try:
                self._loop()
            except Exception:
                if self._stop.is_set():
                    return
                log.exception("%s: a sample or tick handler failed; going on", self.name)
                time.sleep(WAIT_S)

    def _loop(self) -> None:
        from cyclonedds._clayer import ddspy_take
        from cyclonedds.core import InstanceState, SampleState, ViewState
        from cyclonedds.util import duration

        mask = SampleState.Any | ViewState.Any | InstanceState.Any
        next_tick = time.monotonic() + self.tick_s
        while not self._stop.is_set():
            self._waitset.wait(duration(seconds=max(0.001, min(WAIT_S, next_tick - time.monotonic()))))
            self._guard.set(False)
            if self._pending:
                self._attach_pending()
            for index, reader in enumerate(self._readers):
                while True:
                    got = ddspy_take(reader._ref, mask, 64)
                    if isinstance(got, int) or not got:
                        break
                    now = time.time_ns()
                    for data, info in got:
                        if info.valid_data:
                            self.on_sample(index, data, now, info.publication_handle)
            if time.monotonic() >= next_tick:
                next_tick = time.monotonic() + self.tick_s
                if self.on_tick is not None:
                    self.on_tick()

    def stop(self) -> None:
        """End the thread, then delete the readers and the participant. Idempotent."""
        self._stop.set()
        if self._thread is not None:
            self._guard.set(True)
            self._thread.join(10.0)
            self._thread = None
        node, self.node = self.node, None
        if node is not None:  # delete our entities now (as DdsNode does for its own), then the participant
            for ent in [*self._conds, *self._readers, *self._owned, self._guard, self._waitset]:
                ent.__del__()
            self._conds.clear()
            self._readers.clear()
            self._owned.clear()
            node.close()
