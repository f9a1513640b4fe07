"""ROS 2 graph presence, as rmw_cyclonedds does it: our participants show up in ``ros2 node list``/rqt_graph.

A ROS 2 tool learns which nodes exist, and which readers and writers belong to each, from the DDS topic
``ros_discovery_info`` (no ``rt/`` prefix: rmw's own topic, created with avoid_ros_namespace_conventions),
type ``rmw_dds_common/msg/ParticipantEntitiesInfo``, one sample per participant (reliable, transient_local,
keep_last 1), re-published whenever an entity comes or goes. A GID is the entity's 16-byte DDS GUID padded
with zeros to ROS 2 Humble's 24 bytes (robonix's reference image is Humble; Iron and later use 16 bytes and
a different type hash, so a Jazzy node would not match this topic). The participant also carries the USER_DATA
``enclave=/;`` that rmw sets (:data:`PARTICIPANT_USER_DATA`).

One DdsNode is one ROS node here: a provider's node is ``/robonix/<provider id>``; other named DdsNodes
(``rbnx record`` ...) appear under ``/`` with their name.
"""

# no `from __future__ import annotations`: cyclonedds resolves the IDL field annotations at runtime

import re
import threading
from dataclasses import dataclass, field
from typing import Any

from cyclonedds.idl import IdlStruct, types
from cyclonedds.idl.annotations import final
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.topic import Topic
from cyclonedds.util import duration

DISCOVERY_TOPIC = "ros_discovery_info"
PARTICIPANT_USER_DATA = b"enclave=/;"
GID_SIZE = 24  # rmw_dds_common (Humble) Gid: char[24]
NAMESPACE = "/robonix"  # providers' nodes live here
DISCOVERY_QOS = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.Durability.TransientLocal,
                    Policy.History.KeepLast(1))
#: A reader of the topic: the type has no key, so every participant's sample is the same instance and a
#: depth-1 reader would keep only the last one received; read deep and keep the latest per participant GID.
DISCOVERY_READER_QOS = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.Durability.TransientLocal,
                           Policy.History.KeepLast(256))


@final
@dataclass
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    """rmw_dds_common/msg/Gid (Humble): an entity's GUID, zero-padded."""

    data: types.array[types.uint8, GID_SIZE] = field(default_factory=lambda: [0] * GID_SIZE)


@final
@dataclass
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    """rmw_dds_common/msg/NodeEntitiesInfo: one node and the GIDs of its readers and writers."""

    node_namespace: types.bounded_str[256] = ""
    node_name: types.bounded_str[256] = ""
    reader_gid_seq: types.sequence[Gid] = field(default_factory=list)
    writer_gid_seq: types.sequence[Gid] = field(default_factory=list)


@final
@dataclass
class ParticipantEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
    """rmw_dds_common/msg/ParticipantEntitiesInfo: a participant's GID and its nodes."""

    gid: Gid = field(default_factory=Gid)
    node_entities_info_seq: types.sequence[NodeEntitiesInfo] = field(default_factory=list)


def gid_of(entity: Any) -> Gid:
    """An entity's GID: its GUID (network byte order, as ``dds_get_guid`` gives it) padded to 24 bytes."""
    raw = entity.guid.bytes
    return Gid(data=list(raw) + [0] * (GID_SIZE - len(raw)))


def split_node_name(name: str) -> tuple[str, str]:
    """``/robonix/nav2`` -> ('/robonix', 'nav2'); ``rbnx_record`` -> ('/', 'rbnx_record'). Characters a ROS
    node name may not hold (anything but letters, digits and ``_``) become ``_``; a leading digit gets ``_``."""
    ns, _, base = name.strip().rpartition("/")
    base = re.sub(r"[^A-Za-z0-9_]", "_", base) or "node"
    if base[0].isdigit():
        base = "_" + base
    ns = "/" + "/".join(re.sub(r"[^A-Za-z0-9_]", "_", p) for p in ns.split("/") if p)
    return ns, base


def provider_node_name(provider_id: str) -> str:
    """The ROS node name of a provider's DdsNode: ``nav2`` -> ``/robonix/nav2``."""
    return f"{NAMESPACE}/{split_node_name(provider_id)[1]}"


class GraphPresence:
    """The ``ros_discovery_info`` writer of one DdsNode; ``update(readers, writers)`` re-announces it."""

    def __init__(self, participant: Any, node_name: str) -> None:
        self.namespace, self.name = split_node_name(node_name)
        self._participant_gid = gid_of(participant)
        self._topic = Topic(participant, DISCOVERY_TOPIC, ParticipantEntitiesInfo)
        self._writer: DataWriter | None = DataWriter(participant, self._topic, DISCOVERY_QOS)
        self._lock = threading.Lock()

    def update(self, readers: list[Any], writers: list[Any]) -> None:
        """Publish this participant's one node with the GIDs of ``readers`` and ``writers`` (DDS entities)."""
        node = NodeEntitiesInfo(node_namespace=self.namespace, node_name=self.name,
                                reader_gid_seq=[gid_of(r) for r in readers],
                                writer_gid_seq=[gid_of(w) for w in writers])
        with self._lock:
            if self._writer is not None:
                self._writer.write(ParticipantEntitiesInfo(gid=self._participant_gid,
                                                           node_entities_info_seq=[node]))

    def close(self) -> None:
        """Delete the writer (before the participant goes). Idempotent."""
        with self._lock:
            writer, self._writer = self._writer, None
        if writer is not None:
            writer.__del__()
