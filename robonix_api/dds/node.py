"""DdsNode: one DomainParticipant, ROS-named topics, publishers, and callback subscriptions.

Callbacks run on one background thread per node (a WaitSet over the readers' ReadConditions), never on
Cyclone's receive threads, so a slow callback delays only this node's other callbacks, not the network.
Exceptions in callbacks are logged and the thread carries on.

Liveliness: every writer offers automatic liveliness with a short lease (``ROBONIX_DDS_LIVELINESS_S``,
see ``qos.writer_qos``), and every reader tracks which of its matched writers are alive. A writer whose
process was killed or stopped is reported lost after about one lease, and ``on_liveliness(handle,
alive)`` runs on the dispatch thread like data callbacks, so a consumer hears of a dead upstream from
the data plane itself, without polling the atlas.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, Generic, TypeVar

from cyclonedds.core import (
    DDSException,
    GuardCondition,
    InstanceState,
    Listener,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from robonix_api.dds.config import DdsConfigError, resolve_config, resolve_domain_id, summarize
from robonix_api.dds.graph import PARTICIPANT_USER_DATA, GraphPresence
from robonix_api.dds.qos import describe, resolve_qos, writer_qos
from robonix_api.dds.validate import validate_message
from robonix_api.dds.writer_trust import participant_qos

log = logging.getLogger(__name__)
M = TypeVar("M")

_domains_lock = threading.Lock()
_domains: dict[int, tuple[Domain, str, int]] = {}  # domain id -> (Domain, uri, users)


def dds_topic_name(topic: str) -> str:
    """ROS topic '/scan' -> DDS topic 'rt/scan' (ROS 2's prefix for topics)."""
    name = topic.strip().lstrip("/")
    if not name or " " in name:
        raise ValueError(f"invalid topic name {topic!r}")
    return "rt/" + name


def _acquire_domain(domain_id: int) -> tuple[str, dict[str, Any]]:
    """Create (or share) this process's Domain with the validated config; Cyclone allows one per id."""
    uri, source, parsed = resolve_config()
    with _domains_lock:
        if domain_id in _domains:
            dom, used_uri, users = _domains[domain_id]
            _domains[domain_id] = (dom, used_uri, users + 1)
            return used_uri, {"uri": used_uri, "source": source, **summarize(parsed)}
        try:
            dom = Domain(domain_id, uri)
        except DDSException as exc:
            raise DdsConfigError(f"Cyclone DDS rejected config {uri!r} for domain {domain_id}: {exc}") from exc
        _domains[domain_id] = (dom, uri, 1)
    return uri, {"uri": uri, "source": source, **summarize(parsed)}


def _release_domain(domain_id: int) -> None:
    with _domains_lock:
        if domain_id not in _domains:
            return
        dom, uri, users = _domains[domain_id]
        if users > 1:
            _domains[domain_id] = (dom, uri, users - 1)
            return
        del _domains[domain_id]
    dom.__del__()  # dds_delete now, not whenever the GC runs


class Publisher(Generic[M]):
    """A typed DDS writer on ``rt/<topic>``; ``publish`` validates the message first."""

    def __init__(self, node: DdsNode, topic: str, msg_type: type[M], qos: Qos) -> None:
        self.topic, self.msg_type, self.qos = topic, msg_type, qos
        self._node = node
        self._writer: DataWriter | None = DataWriter(node.participant, node._topic(topic, msg_type),
                                                     writer_qos(qos))

    def publish(self, msg: M) -> None:
        """Write ``msg`` on the topic; RuntimeError when closed, TypeError for a message of the wrong type."""
        if self._writer is None:
            raise RuntimeError(f"publisher on {self.topic} is closed")
        if not isinstance(msg, self.msg_type):
            raise TypeError(f"publisher on {self.topic} takes {self.msg_type.__name__}, got {type(msg).__name__}")
        validate_message(msg, self.msg_type)
        self._writer.write(msg)

    emit = publish  # robonix SDK name

    def matched_count(self) -> int:
        """Readers currently matched (discovered, QoS-compatible)."""
        return 0 if self._writer is None else len(self._writer.get_matched_subscriptions())

    def wait_for_subscribers(self, count: int = 1, timeout_s: float = 5.0) -> bool:
        """Wait until ``count`` readers matched (True) or ``timeout_s`` passed (False)."""
        deadline = time.monotonic() + timeout_s
        while self.matched_count() < count:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def close(self) -> None:
        """Delete the writer; later ``publish`` calls raise."""
        w, self._writer = self._writer, None
        if w is not None:
            self._node._forget(self)
            w.__del__()


LivelinessCallback = Callable[[int, bool], Any]


class _LivelinessListener(Listener):
    """Runs on Cyclone's receive thread: only records the change and wakes the node's dispatch thread."""

    def __init__(self, sub: Subscription[Any]) -> None:
        super().__init__()
        self._sub = sub

    def on_liveliness_changed(self, reader: Any, status: Any) -> None:
        # The status carries the handle as a signed 64-bit value, SampleInfo as unsigned: use unsigned.
        handle = status.last_publication_handle & 0xFFFF_FFFF_FFFF_FFFF
        if status.alive_count_change > 0:
            self._sub._liveliness_event(handle, True)
        elif status.alive_count_change < 0:
            self._sub._liveliness_event(handle, False)


class Subscription(Generic[M]):
    """A typed DDS reader whose samples go to ``callback(msg)`` on the node's dispatch thread.

    ``on_liveliness(publication_handle, alive)`` (optional) hears each matched writer become alive and
    lose liveliness (killed, stopped, or deleted); ``alive_writers()`` is the current set. A sample's
    writer is ``msg.sample_info.publication_handle``.
    """

    def __init__(self, node: DdsNode, topic: str, msg_type: type[M], callback: Callable[[M], Any], qos: Qos,
                 on_liveliness: LivelinessCallback | None = None) -> None:
        self.topic, self.msg_type, self.callback, self.qos = topic, msg_type, callback, qos
        self.on_liveliness = on_liveliness
        self._node = node
        self._alive: set[int] = set()
        self._live_events: deque[tuple[int, bool]] = deque()
        self._live_lock = threading.Lock()
        self._listener = _LivelinessListener(self)
        self._reader: DataReader | None = DataReader(node.participant, node._topic(topic, msg_type), qos,
                                                     listener=self._listener)
        self._cond = ReadCondition(self._reader, SampleState.NotRead | ViewState.Any | InstanceState.Any)

    def _liveliness_event(self, handle: int, alive: bool) -> None:
        with self._live_lock:
            if alive:
                self._alive.add(handle)
            else:
                self._alive.discard(handle)
            self._live_events.append((handle, alive))
        self._node._wake()

    def _seen_from(self, handle: int | None) -> None:
        """A sample from a writer proves it alive. Cyclone reports a lost lease and a regained one from
        different threads, so their listener calls can reach us in the wrong order (seen after our own
        process was frozen: a writer stayed 'lost' while its data kept coming); fresh data repairs that."""
        if handle is not None and handle not in self._alive:
            self._liveliness_event(handle, True)

    def alive_writers(self) -> set[int]:
        """Publication handles of the matched writers currently alive (per liveliness QoS)."""
        with self._live_lock:
            return set(self._alive)

    def _drain_liveliness(self) -> None:
        """Run ``on_liveliness`` for each recorded change, in order (dispatch thread only)."""
        while True:
            with self._live_lock:
                if not self._live_events:
                    return
                handle, alive = self._live_events.popleft()
            if self.on_liveliness is None:
                continue
            try:
                self.on_liveliness(handle, alive)
            except Exception:
                log.exception("liveliness callback for %s raised", self.topic)

    def _drain(self) -> None:
        """Take everything pending and run the callback per valid sample (dispatch thread only)."""
        while self._reader is not None:
            try:
                samples = self._reader.take(N=64)
            except Exception:  # malformed sample from a foreign writer: log, keep the node alive
                log.exception("take failed on %s", self.topic)
                return
            if not samples:
                return
            for s in samples:
                info = getattr(s, "sample_info", None)
                if not getattr(info, "valid_data", False):
                    continue
                self._seen_from(getattr(info, "publication_handle", None))
                try:
                    self.callback(s)
                except Exception:
                    log.exception("callback for %s raised", self.topic)

    def matched_count(self) -> int:
        """How many writers this reader is matched with (0 once closed)."""
        return 0 if self._reader is None else len(self._reader.get_matched_publications())

    def close(self) -> None:
        """Delete the reader; no callback runs after this returns."""
        if self._reader is None:
            return
        with self._node._dispatch_lock:
            reader, self._reader = self._reader, None
            self._node._forget(self)
            cond, self._cond = self._cond, None
            cond.__del__()
            reader.__del__()


class DdsNode:
    """One DomainParticipant on ``domain_id`` (default ``ROS_DOMAIN_ID``, else 0)."""

    def __init__(self, domain_id: int | None = None, name: str = "") -> None:
        self.name = name
        self.domain_id = resolve_domain_id(domain_id)
        self.config_uri, self.config = _acquire_domain(self.domain_id)
        try:  # USER_DATA as rmw sets it, plus the deployment's tag (writer_trust); a named node also
            # announces itself on ros_discovery_info (graph.py)
            self.participant = DomainParticipant(self.domain_id, qos=participant_qos(PARTICIPANT_USER_DATA))
        except DDSException as exc:
            _release_domain(self.domain_id)
            raise DdsConfigError(f"cannot create a DDS participant on domain {self.domain_id}: {exc}") from exc
        self._topics: dict[str, tuple[type, Topic]] = {}
        self._entities: list[Publisher[Any] | Subscription[Any]] = []
        self._lock = threading.Lock()
        self._dispatch_lock = threading.RLock()  # held while callbacks run; close() waits for it
        self._waitset: WaitSet | None = None
        self._guard: GuardCondition | None = None
        self._thread: threading.Thread | None = None
        self._closed = False
        self._graph_extra: list[Any] = []  # raw readers/writers made on our participant (announce())
        self._graph = GraphPresence(self.participant, name) if name else None
        self.announce()

    # --- entities ---------------------------------------------------------------------------------
    def _topic(self, topic: str, msg_type: type) -> Topic:
        dds_name = dds_topic_name(topic)
        with self._lock:
            if dds_name in self._topics:
                t_type, t = self._topics[dds_name]
                if t_type is not msg_type:
                    raise TypeError(f"topic {topic} already used with {t_type.__name__} in this node, "
                                    f"not {msg_type.__name__}")
                return t
            t = Topic(self.participant, dds_name, msg_type)
            self._topics[dds_name] = (msg_type, t)
            return t

    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError(f"DdsNode {self.name!r} is closed")

    def create_publisher(self, topic: str, msg_type: type[M], qos: str | Qos = "reliable",
                         depth: int | None = None) -> Publisher[M]:
        """A writer on ``topic`` for ``msg_type`` with a QoS preset (or Qos) and optional history depth."""
        self._check_open()
        pub = Publisher(self, topic, msg_type, resolve_qos(qos, depth))
        with self._lock:
            self._entities.append(pub)
        self.announce()
        return pub

    def create_subscription(self, topic: str, msg_type: type[M], callback: Callable[[M], Any],
                            qos: str | Qos = "best_effort", depth: int | None = None,
                            on_liveliness: LivelinessCallback | None = None) -> Subscription[M]:
        """A reader on ``topic`` that calls ``callback(msg)`` for each sample (and ``on_liveliness`` when writers come
        and go)."""
        self._check_open()
        sub = Subscription(self, topic, msg_type, callback, resolve_qos(qos, depth), on_liveliness)
        self._ensure_dispatcher()
        with self._dispatch_lock:
            with self._lock:
                self._entities.append(sub)
            self._waitset.attach(sub._cond)
        self._guard.set(True)  # let the thread pick up samples that arrived before attach
        self.announce()
        return sub

    def announce(self, *raw_entities: Any) -> None:
        """Publish this node's readers and writers on ros_discovery_info (a named node only), adding
        ``raw_entities``: DataReaders/DataWriters made directly on :attr:`participant`."""
        if self._graph is None or self._closed:
            return
        with self._lock:
            self._graph_extra.extend(raw_entities)
            ents = [e._reader for e in self._entities if isinstance(e, Subscription) and e._reader is not None]
            ents += [e._writer for e in self._entities if isinstance(e, Publisher) and e._writer is not None]
            ents += self._graph_extra
        self._graph.update([e for e in ents if isinstance(e, DataReader)],
                           [e for e in ents if isinstance(e, DataWriter)])

    def unannounce(self, *raw_entities: Any) -> None:
        """Drop raw entities given to :meth:`announce` (before deleting them) and re-announce."""
        with self._lock:
            self._graph_extra = [e for e in self._graph_extra if all(e is not r for r in raw_entities)]
        self.announce()

    def _forget(self, ent: Publisher[Any] | Subscription[Any]) -> None:
        with self._lock:
            if ent in self._entities:
                self._entities.remove(ent)
        self.announce()
        if isinstance(ent, Subscription) and self._waitset is not None and ent._cond is not None:
            with contextlib.suppress(DDSException):
                self._waitset.detach(ent._cond)

    # --- dispatch thread --------------------------------------------------------------------------
    def _wake(self) -> None:
        guard = self._guard
        if guard is not None and not self._closed:
            with contextlib.suppress(DDSException):  # closing concurrently: nobody is left to wake
                guard.set(True)

    def _ensure_dispatcher(self) -> None:
        with self._lock:
            if self._thread is not None:
                return
            self._waitset = WaitSet(self.participant)
            self._guard = GuardCondition(self.participant)
            self._waitset.attach(self._guard)
            self._thread = threading.Thread(target=self._run, name=f"dds-{self.name or 'node'}", daemon=True)
            self._thread.start()

    def _run(self) -> None:
        while not self._closed:
            try:
                self._waitset.wait(duration(milliseconds=500))
            except DDSException:
                if self._closed:
                    return
                raise
            self._guard.set(False)
            with self._dispatch_lock:
                if self._closed:
                    return
                with self._lock:
                    subs = [e for e in self._entities if isinstance(e, Subscription)]
                for s in subs:
                    s._drain_liveliness()
                    s._drain()

    # --- conveniences -----------------------------------------------------------------------------
    def wait_for_message(self, topic: str, msg_type: type[M], timeout_s: float,
                         qos: str | Qos = "reliable") -> M | None:
        """First message on ``topic`` within ``timeout_s`` (latched topics deliver their last one), else None."""
        got: list[M] = []
        ev = threading.Event()

        def cb(m: M) -> None:
            if not got:
                got.append(m)
                ev.set()

        sub = self.create_subscription(topic, msg_type, cb, qos)
        try:
            ev.wait(timeout_s)
        finally:
            sub.close()
        return got[0] if got else None

    def wait_for_topic(self, topic: str, msg_type: type, timeout_s: float) -> bool:
        """True once some writer on ``topic`` is discovered (a best-effort reader matches any writer)."""
        sub = self.create_subscription(topic, msg_type, lambda m: None, "best_effort")
        try:
            deadline = time.monotonic() + timeout_s
            while sub.matched_count() == 0:
                if time.monotonic() > deadline:
                    return False
                time.sleep(0.01)
            return True
        finally:
            sub.close()

    def qos_of(self, ent: Publisher[Any] | Subscription[Any]) -> dict[str, object]:
        """The QoS a publisher or subscription actually uses, as a plain dict (for diagnostics)."""
        return describe(ent.qos)

    def close(self) -> None:
        """Stop the dispatch thread, delete all entities and the participant. Idempotent."""
        if self._closed:
            return
        self._closed = True
        if self._guard is not None:
            self._guard.set(True)
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
        with self._dispatch_lock:
            if self._graph is not None:
                self._graph.close()
            for ent in list(self._entities):
                ent.close()
            self._topics.clear()
            self.participant.__del__()
        _release_domain(self.domain_id)

    def __enter__(self) -> DdsNode:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
