"""Live Foxglove view of every DDS topic: `rbnx boot --foxglove [PORT]` serves ``ws://127.0.0.1:PORT``.

Built on the PyPI ``foxglove-sdk`` WebSocket server, behind :mod:`rbnx.foxglove_shim` so clients may offer
either name of the protocol (``foxglove.websocket.v1`` or ``foxglove.sdk.v1``). Each DDS topic
of a type we know (:data:`rbnx.rosmsg.TYPES`) becomes a channel with its ``ros2msg`` schema and ``cdr``
encoding; the bytes sent are the wire bytes a :class:`rbnx.ddstap.RawTap` received, so Foxglove decodes
them exactly as it decodes a ROS 2 bridge. Topics are found by DDS discovery (the writers' publication
data, as ``ros2 topic list`` does) and added while running. Latched topics (transient_local: /map,
/tf_static) keep their last sample per writer and re-send it to a client that subscribes late, which a
plain forwarder would not (a late Foxglove panel would show no map until SLAM published again).
"""

from __future__ import annotations

import sys
import threading
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rbnx.rosmsg import TopicSpec

DEFAULT_PORT = 8766  # the dashboard's is 8765
TICK_S = 0.2  # discovery and late-subscriber re-sends run this often


class FoxgloveBridge:
    """DDS -> Foxglove WebSocket. ``start`` binds the server (OSError if the port is taken); ``stop`` ends it."""

    def __init__(self, port: int = DEFAULT_PORT, *, host: str = "127.0.0.1", domain_id: int | None = None,
                 specs: list[TopicSpec] | None = None, discover: bool = True) -> None:
        self.host = host
        self.port = port
        self.domain_id = domain_id
        self.discover = discover
        self._initial = list(specs or [])
        self._topics: set[str] = set()
        self._channels: list[Any] = []  # foxglove Channel per tap index
        self._by_channel_id: dict[int, int] = {}  # foxglove channel id -> tap index
        self._latched: dict[int, dict[int, tuple[bytes, int]]] = {}  # tap index -> writer -> (bytes, recv ns)
        self._resend: set[int] = set()  # tap indices a client subscribed to since the last tick
        self._lock = threading.Lock()
        self._server: Any = None
        self._shim: Any = None
        self._tap: Any = None
        self._pub_reader: Any = None
        self._context: Any = None

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def start(self) -> None:
        import foxglove

        from rbnx.ddstap import RawTap
        from rbnx.foxglove_shim import SubprotocolShim

        self._context = foxglove.Context()
        # the SDK server on a private ephemeral loopback port; the public port is the shim's
        self._server = foxglove.start_server(name="robonix-nav", host="127.0.0.1", port=0,
                                             context=self._context, server_listener=self)
        self._shim = SubprotocolShim(f"ws://127.0.0.1:{self._server.port}", self.host, self.port)
        self._shim.start()
        self.port = self._shim.port
        self._tap = RawTap([], self._on_sample, domain_id=self.domain_id, name="rbnx_foxglove",
                           tick_s=TICK_S, on_tick=self._tick)
        for s in self._initial:
            self._add(s)
        self._tap.start()
        if self.discover:
            from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication

            self._pub_reader = self._tap.own(
                BuiltinDataReader(self._tap.node.participant, BuiltinTopicDcpsPublication))

    def _add(self, spec: TopicSpec) -> None:
        """A channel for ``spec`` (created before the tap's reader, so no sample finds it missing)."""
        import foxglove

        from rbnx.record import qos_metadata
        from rbnx.rosmsg import ros_name, schema_text

        schema = foxglove.Schema(name=ros_name(spec.msg_type), encoding="ros2msg",
                                 data=schema_text(spec.msg_type).encode())
        channel = foxglove.Channel(spec.topic, schema=schema, message_encoding="cdr", context=self._context,
                                   metadata={"offered_qos_profiles": qos_metadata(spec.qos)})
        with self._lock:
            index = len(self._channels)
            self._channels.append(channel)
            self._by_channel_id[channel.id()] = index
            if spec.qos == "latched":
                self._latched[index] = {}
            self._topics.add(spec.topic)
        self._tap.add(spec)  # its index is ``index``: channels and readers are only added here, in order

    def _on_sample(self, index: int, data: bytes, recv_ns: int, writer: int) -> None:
        latched = self._latched.get(index)
        if latched is not None:
            with self._lock:
                latched[writer] = (data, recv_ns)
        self._channels[index].log(data, log_time=recv_ns)

    def _tick(self) -> None:
        if self._pub_reader is not None:
            from rbnx.record import spec_from_publication

            for pub in self._pub_reader.take(N=256):
                spec = spec_from_publication(pub)
                if spec is not None and spec.topic not in self._topics:
                    self._add(spec)
        with self._lock:
            resend, self._resend = self._resend, set()
            samples = [(i, list(self._latched[i].values())) for i in resend if i in self._latched]
        for index, held in samples:
            for data, recv_ns in held:
                self._channels[index].log(data, log_time=recv_ns)

    def held_latched(self, topic: str) -> int:
        """How many writers' last samples the bridge holds for a latched ``topic`` (0 if none or not latched)."""
        with self._lock:
            return sum(len(self._latched.get(i, {})) for i, ch in enumerate(self._channels) if ch.topic() == topic)

    # foxglove ServerListener
    def on_subscribe(self, client: Any, channel: Any) -> None:
        """A client subscribed: re-send the latched samples on the next tick (the server registers the
        subscription after this callback; the other subscribers get a harmless duplicate)."""
        with self._lock:
            index = self._by_channel_id.get(channel.id)
            if index is not None and index in self._latched:
                self._resend.add(index)

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        """Nothing to do: the server stops sending; latched samples stay held for the next subscriber."""

    def stop(self) -> None:
        """Stop the DDS side, then the server. Idempotent."""
        tap, self._tap = self._tap, None
        if tap is not None:
            tap.stop()
            self._pub_reader = None
        shim, self._shim = self._shim, None
        if shim is not None:
            shim.stop()
        server, self._server = self._server, None
        if server is not None:
            server.stop()


def start_for_cli(port: int | None, prog: str, domain_id: int | None = None) -> tuple[FoxgloveBridge | None, int]:
    """(bridge, 0) serving on 127.0.0.1:``port``, printing its ``ws://`` address; (None, 0) when ``port`` is
    None (not asked for); (None, 2) with a one-line error for a bad or taken port."""
    if port is None:
        return None, 0
    if not 0 <= port <= 65535:
        print(f"{prog}: --foxglove: port must be 0..65535, got {port}", file=sys.stderr)
        return None, 2
    try:
        import foxglove  # noqa: F401 - an optional dependency
    except ImportError:
        print(f"{prog}: --foxglove: needs foxglove-sdk: pip install 'robonix-nav[foxglove]'", file=sys.stderr)
        return None, 2
    bridge = FoxgloveBridge(port, domain_id=domain_id)
    try:
        bridge.start()
    except Exception as exc:  # the SDK raises its own error type for a taken port
        bridge.stop()
        print(f"{prog}: --foxglove: cannot serve on 127.0.0.1:{port}: {exc}", file=sys.stderr)
        return None, 2
    print(f"foxglove at {bridge.url}", flush=True)
    return bridge, 0
