"""A real Cyclone writer emits our messages as XCDR1 (CDR_LE), byte for byte what we serialise."""

from __future__ import annotations

import robonix_api.dds.messages as m
from robonix_api.dds import DdsNode

HDR = b"\x00\x01\x00\x00"


def test_writer_emits_xcdr1_on_the_wire(node: DdsNode) -> None:
    """Take the raw sample as delivered through Cyclone: encapsulation must be CDR_LE (XCDR1)."""
    from cyclonedds._clayer import ddspy_take
    from cyclonedds.core import InstanceState, SampleState, ViewState
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from robonix_api.dds.qos import qos_profile

    pub = node.create_publisher("/wire_check", m.Twist, "reliable")
    assert pub._writer._use_version_2 is False
    reader = DataReader(node.participant, Topic(node.participant, "rt/wire_check", m.Twist), qos_profile("reliable"))
    msg = m.Twist(linear=m.Vector3(1.0, 2.0, 3.0))
    pub.publish(msg)
    got = ddspy_take(reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, 1)
    assert got
    assert got[0][0][:4] == HDR
    assert got[0][0][:52] == msg.serialize()
