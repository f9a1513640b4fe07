"""ROS 2 message names on the DDS data plane: robonix-api's ``resolve_msg_type`` without rclpy.

robonix-api passes message types around by ROS name (``"LaserScan"``, ``"sensor_msgs/msg/LaserScan"``)
and resolves them to rclpy classes. Here the same names resolve to this SDK's Cyclone DDS classes
(``robonix_api.dds.messages``), which carry ROS 2's DDS type names, so a ROS 2 node on the same domain
still sees ``sensor_msgs/msg/LaserScan``. ``RosBackend`` keeps robonix-api's process-wide singleton
shape, backed by one :class:`~robonix_api.dds.DdsNode` instead of an rclpy node.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from typing import Any

from robonix_api.dds.qos import QOS_NAMES

#: Tried in this order for a bare class name, as robonix-api does.
BARE_NAME_PACKAGES = ("sensor_msgs", "std_msgs", "geometry_msgs", "nav_msgs")


@functools.cache
def _catalogue() -> dict[tuple[str, str], type]:
    """``(ros package, type name) -> class`` for every message class of the data plane."""
    from robonix_api.dds import messages

    out: dict[tuple[str, str], type] = {}
    for value in vars(messages).values():
        typename = getattr(value, "__idl_typename__", None)
        if not isinstance(value, type) or not isinstance(typename, str) or "::dds_::" not in typename:
            continue
        pkg, _, rest = typename.partition("::msg::dds_::")
        out[(pkg, rest.rstrip("_"))] = value
    return out


def resolve_msg_type(name: str | type) -> type:
    """``"LaserScan"`` / ``"sensor_msgs/LaserScan"`` / ``"sensor_msgs/msg/LaserScan"`` -> message class.

    A class is returned unchanged. As in robonix-api: a malformed slash name is ``ValueError``, an
    unknown type ``ImportError`` (naming the type and where it was looked for).
    """
    if isinstance(name, type):
        return name
    n = str(name).strip()
    cat = _catalogue()
    if "/" in n:
        parts = [p for p in n.split("/") if p and p != "msg"]
        if len(parts) != 2:
            raise ValueError(f"unrecognized msg type {name!r} (expected pkg/msg/Type, pkg/Type or Type)")
        cls = cat.get((parts[0], parts[1]))
        if cls is None:
            raise ImportError(f"msg type {name!r} is not available on the DDS data plane "
                              f"(known: {', '.join(sorted(f'{p}/msg/{t}' for p, t in cat))})")
        return cls
    for pkg in (*BARE_NAME_PACKAGES, *sorted({p for p, _ in cat} - set(BARE_NAME_PACKAGES))):
        cls = cat.get((pkg, n))
        if cls is not None:
            return cls
    raise ImportError(f"could not locate msg type {name!r} in {BARE_NAME_PACKAGES} "
                      "(or the other packages of the DDS data plane)")


def qos_and_depth(qos: str | int | Any) -> tuple[Any, int | None]:
    """robonix-api's QoS spec -> this data plane's ``(preset or Qos, depth)``.

    A name is a preset (robonix-api's three plus ``transient_local``, ``sensor_data``, ``clock``); an
    int is a KEEP_LAST depth with RELIABLE, VOLATILE (as robonix-api); a cyclonedds ``Qos`` passes
    through. robonix-api quietly treats an unknown name as ``reliable``; here it is a ``ValueError``.
    """
    if isinstance(qos, bool):
        raise TypeError(f"qos: expected a preset name or a depth, got {qos!r}")
    if isinstance(qos, int):
        if qos < 1:
            raise ValueError(f"qos: a depth must be >= 1, got {qos}")
        return "reliable", qos
    if isinstance(qos, str) and qos not in QOS_NAMES:
        raise ValueError(f"qos: unknown QoS preset {qos!r}; valid: {', '.join(QOS_NAMES)} or a depth (int)")
    return qos, None


def declared_qos(qos: str | int | Any) -> str:
    """The QoS name declared to the atlas (robonix-api declares an int depth as ``reliable``)."""
    return qos if isinstance(qos, str) else "reliable"


class RosBackend:
    """One data-plane node per process (robonix-api's ``RosBackend`` over rclpy; here a ``DdsNode``).

    Providers use their own node (``provider.dds_node()``); this is for code written against
    robonix-api's ``RosBackend.get().create_publisher(...)``. ``msg_type`` may be a class or a ROS name.
    """

    _instance: RosBackend | None = None
    _instance_lock = threading.Lock()

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._node: Any = None

    @classmethod
    def get(cls) -> RosBackend:
        """The one backend of this process (created on first use)."""
        with cls._instance_lock:
            if cls._instance is None:
                cls._instance = RosBackend()
            return cls._instance

    @property
    def node(self) -> Any:
        """The process's ``DdsNode`` (created on first use)."""
        with self._lock:
            if self._node is None:
                from robonix_api.dds import DdsNode

                self._node = DdsNode(name="robonix_capability")
            return self._node

    def create_publisher(self, msg_type: type | str, topic: str, qos: Any = 10) -> Any:
        """rclpy-style ``create_publisher(msg_type, topic, qos)`` on the process's DDS node."""
        preset, depth = qos_and_depth(qos)
        return self.node.create_publisher(topic, resolve_msg_type(msg_type), preset, depth)

    def create_subscription(self, msg_type: type | str, topic: str, callback: Callable[[Any], None],
                            qos: Any = 10) -> Any:
        """rclpy-style ``create_subscription(msg_type, topic, callback, qos)`` on the process's DDS node."""
        preset, depth = qos_and_depth(qos)
        return self.node.create_subscription(topic, resolve_msg_type(msg_type), callback, preset, depth)

    def wait_for_topic(self, topic: str, msg_type: type | str, timeout_s: float) -> bool:
        """True once a first message arrives (best-effort reader), as robonix-api."""
        return self.node.wait_for_message(topic, resolve_msg_type(msg_type), timeout_s, "best_effort") is not None

    @staticmethod
    def qos(spec: Any) -> Any:
        """A QoS spec (name, depth or cyclonedds ``Qos``) as a cyclonedds ``Qos``."""
        from robonix_api.dds.qos import resolve_qos

        preset, depth = qos_and_depth(spec)
        return resolve_qos(preset, depth)

    def shutdown(self) -> None:
        """Close the DDS node (its publishers and subscriptions); a later call creates a new one."""
        with self._lock:
            node, self._node = self._node, None
        if node is not None:
            node.close()


__all__ = ["BARE_NAME_PACKAGES", "RosBackend", "declared_qos", "qos_and_depth", "resolve_msg_type"]
