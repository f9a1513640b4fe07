"""Topic helpers on a provider over the real DDS data plane (loopback, per-run domain id)."""

from __future__ import annotations

import os
import threading

import pytest
from support.fakes import FakeAtlas
from support.procs import wait_until

from robonix_api import Service
from robonix_api.types import Ros2Params, Transport

ODOM = "robonix/primitive/chassis/odom"


def test_publisher_declared_and_emitted(fake_atlas: FakeAtlas, clean_env: None, short_heartbeat: float) -> None:
    dds = pytest.importorskip("robonix_api.dds")
    topic = f"/sdk_test_twist_{os.getpid()}"
    svc = Service("topics_p", "robonix/test", atlas=fake_atlas)
    svc.run_in_thread()
    try:
        svc.create_publisher(ODOM, topic=topic, msg_type=dds.Twist, qos="reliable")
        decl = fake_atlas.declared[("topics_p", ODOM, Transport.ROS2)]
        assert decl["endpoint"] == topic
        assert decl["params"] == Ros2Params("reliable")
        got: list[object] = []
        seen = threading.Event()
        svc.create_subscription(ODOM, topic=topic, msg_type=dds.Twist, qos="reliable",
                                callback=lambda m: (got.append(m), seen.set()))
        assert svc.wait_for_writer(topic, dds.Twist, timeout_s=30)
        msg = dds.Twist(linear=dds.Vector3(x=0.25, y=0.0, z=0.0), angular=dds.Vector3(x=0.0, y=0.0, z=0.5))

        def delivered() -> bool:
            svc.emit(ODOM, msg)
            return seen.wait(0.2)

        wait_until(delivered, what="a Twist through DDS")
        assert got[0].linear.x == 0.25
    finally:
        svc.stop()
