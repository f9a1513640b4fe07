"""ROS 2 graph presence over real DDS: ros_discovery_info samples, read raw from another participant and
decoded with rosbags' own rmw_dds_common (Humble) type, name each node with the GIDs of its readers and
writers, which match the GUIDs DDS discovery reports for its topics; participants carry USER_DATA
``enclave=/;``; the sample follows entities coming and going."""

from __future__ import annotations

from typing import Any

import pytest
from cyclonedds.builtin import (
    BuiltinDataReader,
    BuiltinTopicDcpsParticipant,
    BuiltinTopicDcpsPublication,
    BuiltinTopicDcpsSubscription,
)
from cyclonedds.qos import Policy
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from support.procs import wait_until

from robonix_api.dds import DdsNode, LaserScan, Odometry, Twist
from robonix_api.dds.graph import (
    DISCOVERY_READER_QOS,
    DISCOVERY_TOPIC,
    ParticipantEntitiesInfo,
    provider_node_name,
    split_node_name,
)

pytestmark = pytest.mark.timeout(120)


def test_node_names_follow_ros_rules() -> None:
    assert split_node_name("/robonix/nav2") == ("/robonix", "nav2")
    assert split_node_name("rbnx_record") == ("/", "rbnx_record")
    assert split_node_name("/a-b/9lives.x") == ("/a_b", "_9lives_x")
    assert provider_node_name("panda-mobile") == "/robonix/panda_mobile"


class _GraphWatcher:
    """A separate participant reading ros_discovery_info as raw CDR, decoded with rosbags (Humble)."""

    def __init__(self, node: DdsNode) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.ROS2_HUMBLE)
        self.node = node
        self.reader = DataReader(node.participant, Topic(node.participant, DISCOVERY_TOPIC, ParticipantEntitiesInfo),
                                 DISCOVERY_READER_QOS)
        self.latest: dict[bytes, Any] = {}  # participant gid -> decoded sample

    def poll(self) -> dict[tuple[str, str], Any]:
        from cyclonedds._clayer import ddspy_take
        from cyclonedds.core import InstanceState, SampleState, ViewState

        got = ddspy_take(self.reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, 64)
        for data, info in got if not isinstance(got, int) else []:
            if info.valid_data:
                msg = self.store.deserialize_cdr(data, "rmw_dds_common/msg/ParticipantEntitiesInfo")
                self.latest[bytes(msg.gid.data)] = msg
        return {(n.node_namespace, n.node_name): n for m in self.latest.values() for n in m.node_entities_info_seq}


def _gid(entity: Any) -> bytes:
    return entity.guid.bytes + bytes(8)


def test_ros_discovery_info_lists_nodes_readers_and_writers() -> None:
    with DdsNode(name="/robonix/nav2") as nav, DdsNode(name="watcher") as w:
        cmd = nav.create_publisher("/cmd_vel", Twist, "reliable")
        odom = nav.create_subscription("/odom", Odometry, lambda _m: None, "reliable")
        watcher = _GraphWatcher(w)
        wait_until(lambda: len(getattr(watcher.poll().get(("/robonix", "nav2")), "writer_gid_seq", [])) == 1,
                   30, lambda: f"nodes seen: {sorted(watcher.poll())}")
        info = watcher.poll()[("/robonix", "nav2")]
        assert [bytes(g.data) for g in info.writer_gid_seq] == [_gid(cmd._writer)]
        assert [bytes(g.data) for g in info.reader_gid_seq] == [_gid(odom._reader)]
        sample = next(m for m in watcher.latest.values() if m.node_entities_info_seq[0].node_name == "nav2")
        assert bytes(sample.gid.data) == _gid(nav.participant)
        # the GIDs are the ones DDS discovery reports for the topics (how ros2 node info maps them)
        pubs = {p.key.bytes + bytes(8): p.topic_name
                for p in BuiltinDataReader(w.participant, BuiltinTopicDcpsPublication).take(N=256)}
        subs = {s.key.bytes + bytes(8): s.topic_name
                for s in BuiltinDataReader(w.participant, BuiltinTopicDcpsSubscription).take(N=256)}
        assert pubs[bytes(info.writer_gid_seq[0].data)] == "rt/cmd_vel"
        assert subs[bytes(info.reader_gid_seq[0].data)] == "rt/odom"
        parts = BuiltinDataReader(w.participant, BuiltinTopicDcpsParticipant).take(N=64)
        nav_part = next(p for p in parts if p.key == nav.participant.guid)
        assert nav_part.qos[Policy.Userdata].data == b"enclave=/;"

        # a new entity re-announces; a closed one disappears
        scan = nav.create_subscription("/scan", LaserScan, lambda _m: None, "best_effort")
        wait_until(lambda: len(watcher.poll()[("/robonix", "nav2")].reader_gid_seq) == 2, 30, "second reader")
        cmd.close()
        wait_until(lambda: len(watcher.poll()[("/robonix", "nav2")].writer_gid_seq) == 0, 30, "writer gone")
        assert {bytes(g.data) for g in watcher.poll()[("/robonix", "nav2")].reader_gid_seq} == {
            _gid(odom._reader), _gid(scan._reader)}


def test_unnamed_node_announces_nothing_but_has_user_data() -> None:
    with DdsNode() as anon, DdsNode(name="watcher") as w:
        anon.create_publisher("/cmd_vel", Twist, "reliable")
        watcher = _GraphWatcher(w)
        wait_until(lambda: ("/", "watcher") in watcher.poll(), 30, "the watcher's own node")
        assert all(bytes(m.gid.data) != _gid(anon.participant) for m in watcher.latest.values())
        parts = BuiltinDataReader(w.participant, BuiltinTopicDcpsParticipant).take(N=64)
        assert next(p for p in parts if p.key == anon.participant.guid).qos[Policy.Userdata].data == b"enclave=/;"
