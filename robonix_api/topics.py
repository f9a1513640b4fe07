"""Topic helpers on a provider: publishers/subscriptions on the DDS data plane, declared to the atlas.

Thin on purpose: the data plane lives in ``robonix_api.dds`` (imported lazily, so a provider with no
topics never loads Cyclone DDS); here we only tie a topic to its contract and the atlas.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)


class NoPublisherError(RuntimeError, KeyError):
    """``emit`` before ``create_publisher``: a ``RuntimeError`` as in robonix-api (and a ``KeyError``, as
    this SDK raised before)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class TopicsMixin:
    """Mixed into providers; needs ``declare_ros2_topic`` and ``atlas``/``id`` from the host class."""

    def __init__(self) -> None:
        self._dds_node: Any = None
        self._dds_lock = threading.Lock()
        self._publishers: dict[str, Any] = {}
        self._subscriptions: list[Any] = []

    def dds_node(self) -> Any:
        """This provider's one ``DdsNode`` (created on first use), the ROS node ``/robonix/<id>``."""
        with self._dds_lock:
            if self._dds_node is None:
                from robonix_api.dds import DdsNode
                from robonix_api.dds.graph import provider_node_name

                self._dds_node = DdsNode(name=provider_node_name(str(getattr(self, "id", "") or "provider")))
            return self._dds_node

    def create_publisher(self, contract_id: str, *, topic: str, msg_type: type | str,
                         qos: str | int = "best_effort", declare: bool = True, description: str = "") -> Any:
        """Publish ``msg_type`` (a class or a ROS name such as ``"LaserScan"``) for a topic_out contract;
        declared first so an atlas rename is honoured. ``qos``: a preset name or a depth (int)."""
        from robonix_api.ros import declared_qos, qos_and_depth, resolve_msg_type

        cls = resolve_msg_type(msg_type)
        preset, depth = qos_and_depth(qos)
        if declare:
            topic = self.declare_ros2_topic(contract_id, topic, qos=declared_qos(qos),  # type: ignore[attr-defined]
                                            description=description)
        pub = self.dds_node().create_publisher(topic, cls, preset, depth)
        self._publishers[contract_id] = pub
        return pub

    def emit(self, contract_id: str, msg: Any) -> None:
        """Publish on the contract's publisher (``create_publisher`` first)."""
        pub = self._publishers.get(contract_id)
        if pub is None:
            raise NoPublisherError(f"no publisher for contract {contract_id!r} -- call create_publisher(...) first")
        pub.publish(msg)

    def create_subscription(self, contract_id: str, *, topic: str = "", msg_type: type | str,
                            callback: Callable[[Any], None], qos: str | int = "best_effort",
                            declare: bool = False, provider_id: str = "") -> Any:
        """Subscribe to a topic; with no ``topic``, resolve the contract's provider through the atlas.

        ``declare=True`` also declares the topic under ``contract_id`` (robonix-api's default; off here
        because a consumer declared as offering its input makes ``find_unique_capability`` ambiguous).
        """
        from robonix_api.ros import declared_qos, qos_and_depth, resolve_msg_type

        cls = resolve_msg_type(msg_type)
        if not topic:
            topic, qos = self._resolve_topic(contract_id, provider_id, declared_qos(qos))
        elif declare:
            try:
                self.declare_ros2_topic(contract_id, topic, qos=declared_qos(qos))  # type: ignore[attr-defined]
            except Exception as exc:  # optional for a consumer, as in robonix-api
                log.warning("create_subscription(%s): declare failed: %s", contract_id, exc)
        preset, depth = qos_and_depth(qos)
        sub = self.dds_node().create_subscription(topic, cls, callback, preset, depth)
        self._subscriptions.append(sub)
        return sub

    def create_subscription_from_channel(self, channel: Any, *, msg_type: type | str,
                                         callback: Callable[[Any], None]) -> Any:
        """Subscribe to the topic a ``connect_capability`` channel points at, with the QoS the provider
        declared (a best-effort writer is never matched by a reliable reader)."""
        from robonix_api.ros import qos_and_depth, resolve_msg_type

        qos_name = getattr(channel.params, "qos_profile", "") or "best_effort"
        preset, depth = qos_and_depth(qos_name)
        sub = self.dds_node().create_subscription(channel.endpoint, resolve_msg_type(msg_type), callback,
                                                  preset, depth)
        self._subscriptions.append(sub)
        return sub

    def _resolve_topic(self, contract_id: str, provider_id: str, qos: str) -> tuple[str, str]:
        atlas = self.atlas  # type: ignore[attr-defined]
        if not provider_id:
            cap = atlas.find_unique_capability(contract_id=contract_id, transport="ros2")
            provider_id = cap.provider_id
        ch = atlas.connect_capability(consumer_id=self.id, provider_id=provider_id,  # type: ignore[attr-defined]
                                      contract_id=contract_id, transport="ros2")
        with ch:
            return ch.endpoint, (getattr(ch.params, "qos_profile", "") or qos)

    def wait_for_topic(self, topic: str, msg_type: type | str, timeout_s: float = 30.0) -> bool:
        """True once a first message arrives on ``topic`` within ``timeout_s`` (robonix-api's meaning: a
        best-effort reader, so it matches any writer). :meth:`wait_for_writer` only waits for discovery."""
        from robonix_api.ros import resolve_msg_type

        cls = resolve_msg_type(msg_type)
        return self.dds_node().wait_for_message(topic, cls, timeout_s, "best_effort") is not None

    def wait_for_writer(self, topic: str, msg_type: type | str, timeout_s: float = 30.0) -> bool:
        """True once a writer on ``topic`` is discovered within ``timeout_s`` (no message needed)."""
        from robonix_api.ros import resolve_msg_type

        return bool(self.dds_node().wait_for_topic(topic, resolve_msg_type(msg_type), timeout_s))

    def wait_for_message(self, topic: str, msg_type: type | str, timeout_s: float = 10.0,
                         qos: str = "reliable") -> Any | None:
        """The first message on ``topic`` within ``timeout_s`` (a latched topic gives its last), else None."""
        from robonix_api.ros import resolve_msg_type

        return self.dds_node().wait_for_message(topic, resolve_msg_type(msg_type), timeout_s, qos)

    def close_topics(self) -> None:
        """Close publishers, subscriptions and the node (provider teardown)."""
        for item in [*self._publishers.values(), *self._subscriptions]:
            _close(item)
        self._publishers.clear()
        self._subscriptions.clear()
        with self._dds_lock:
            node, self._dds_node = self._dds_node, None
        if node is not None:
            node.close()


def _close(item: Any) -> None:
    for name in ("close", "destroy"):
        fn = getattr(item, name, None)
        if callable(fn):
            fn()
            return
