"""What ``ros2 node list`` / ``ros2 node info`` would show for a running deploy, read the way rmw does it.

    ROS_DOMAIN_ID=<the deploy's> python bench/ros_graph.py [--wait 5]

Reads ``ros_discovery_info`` as raw CDR and decodes it with rosbags' own rmw_dds_common type (ROS 2 Humble),
then maps each node's reader and writer GIDs to topics through DDS discovery (DCPSPublication /
DCPSSubscription), as rmw_dds_common's graph cache does. Prints one block per node; exit 1 if no node.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--wait", type=float, default=5.0, help="seconds of discovery before printing")
    args = ap.parse_args()
    from cyclonedds._clayer import ddspy_take
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription
    from cyclonedds.core import InstanceState, SampleState, ViewState
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from rosbags.typesys import Stores, get_typestore

    from robonix_api.dds import DdsNode
    from robonix_api.dds.graph import DISCOVERY_READER_QOS, DISCOVERY_TOPIC, ParticipantEntitiesInfo

    store = get_typestore(Stores.ROS2_HUMBLE)
    with DdsNode() as node:  # unnamed: this tool does not show itself in the graph
        p = node.participant
        reader = DataReader(p, Topic(p, DISCOVERY_TOPIC, ParticipantEntitiesInfo), DISCOVERY_READER_QOS)
        pubs_r = BuiltinDataReader(p, BuiltinTopicDcpsPublication)
        subs_r = BuiltinDataReader(p, BuiltinTopicDcpsSubscription)
        time.sleep(args.wait)
        got = ddspy_take(reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, 256)
        latest = {}
        for data, info in got if not isinstance(got, int) else []:
            if info.valid_data:
                msg = store.deserialize_cdr(data, "rmw_dds_common/msg/ParticipantEntitiesInfo")
                latest[bytes(msg.gid.data)] = msg
        pubs = {s.key.bytes + bytes(8): (s.topic_name, s.type_name) for s in pubs_r.take(N=1024)}
        subs = {s.key.bytes + bytes(8): (s.topic_name, s.type_name) for s in subs_r.take(N=1024)}
        for ent in (reader, pubs_r, subs_r):
            ent.__del__()

    def show(gids: list, table: dict) -> list[str]:
        out = []
        for g in gids:
            topic, typ = table.get(bytes(g.data), ("?", "?"))
            ns, _, rest = typ.partition("::dds_::")  # nav2_msgs::action::dds_::X_ -> nav2_msgs/action/X
            out.append(f"    {topic.removeprefix('rt')}: {ns.replace('::', '/')}/{rest.rstrip('_')}")
        return sorted(out)

    nodes = sorted((n.node_namespace, n.node_name, n) for m in latest.values() for n in m.node_entities_info_seq)
    for ns, name, n in nodes:
        print(f"{ns.rstrip('/')}/{name}")
        print("  Subscribers:", *show(n.reader_gid_seq, subs), sep="\n")
        print("  Publishers:", *show(n.writer_gid_seq, pubs), sep="\n")
    print(f"{len(nodes)} nodes from {len(latest)} participants")
    return 0 if nodes else 1


if __name__ == "__main__":
    sys.exit(main())
