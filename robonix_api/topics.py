"""Topic helpers on a provider: publishers/subscriptions on the DDS data plane, declared to the atlas.

Thin on purpose: the data plane lives in ``robonix_api.dds`` (imported lazily, so a provider with no
topics never loads Cyclone DDS); here we only tie a topic to its contract and the atlas.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


class TopicsMixin:
    """Mixed into providers; needs ``declare_ros2_topic`` and ``atlas``/``id`` from the host class."""

    def __init__(self) -> None:
        self._dds_node: Any = None
        self._dds_lock = threading.Lock()
        self._publishers: dict[str, Any] = {}
        self._subscriptions: list[Any] = []

    def dds_node(self) -> Any:
        """This provider's one ``DdsNode`` (created on first use)."""
        with self._dds_lock:
            if self._dds_node is None:
                from robonix_api.dds import DdsNode

                self._dds_node = DdsNode()
            return self._dds_node

    def create_publisher(self, contract_id: str, *, topic: str, msg_type: type, qos: str = "best_effort",
                         declare: bool = True) -> Any:
        """Publish ``msg_type`` for a topic_out contract; declared first so an atlas rename is honoured."""
        if declare:
            topic = self.declare_ros2_topic(contract_id, topic, qos=qos)  # type: ignore[attr-defined]
        pub = self.dds_node().create_publisher(topic, msg_type, qos)
        self._publishers[contract_id] = pub
        return pub

    def emit(self, contract_id: str, msg: Any) -> None:
        """Publish on the contract's publisher (``create_publisher`` first)."""
        try:
            pub = self._publishers[contract_id]
        except KeyError:
            raise KeyError(f"emit({contract_id!r}): no publisher; call create_publisher first") from None
        pub.publish(msg)

    def create_subscription(self, contract_id: str, *, topic: str = "", msg_type: type,
                            callback: Callable[[Any], None], qos: str = "best_effort",
                            provider_id: str = "") -> Any:
        """Subscribe to a topic; with no ``topic``, resolve the contract's provider through the atlas."""
        if not topic:
            topic, qos = self._resolve_topic(contract_id, provider_id, qos)
        sub = self.dds_node().create_subscription(topic, msg_type, callback, qos)
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

    def wait_for_topic(self, topic: str, msg_type: type, timeout_s: float = 10.0) -> bool:
        """True once a writer on ``topic`` is discovered within ``timeout_s``."""
        return bool(self.dds_node().wait_for_topic(topic, msg_type, timeout_s))

    def wait_for_message(self, topic: str, msg_type: type, timeout_s: float = 10.0,
                         qos: str = "reliable") -> Any | None:
        """The first message on ``topic`` within ``timeout_s`` (a latched topic gives its last), else None."""
        return self.dds_node().wait_for_message(topic, msg_type, timeout_s, qos)

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
