"""UpstreamWatch against a real in-process atlas: TERMINATED marks an input lost, a provider missing from a
restarted atlas does not, and a provider registered anew with another topic is followed."""

from __future__ import annotations

from atlas.server import AtlasServer
from nav2_wrapper.upstream import MAP, ODOM, TWIST_IN, UpstreamWatch
from robonix_api.atlas_client import AtlasClient
from robonix_api.upstream import Binding


def _register(c: AtlasClient, pid: str, contract: str, topic: str) -> None:
    c.register("service", pid, "robonix/service/map")
    c.declare_capability(pid, contract, "ros2", topic)


def test_upstream_watch_terminated_absent_and_reregistered_elsewhere() -> None:
    server = AtlasServer(listen="127.0.0.1:0", heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    addr = server.start()
    try:
        with AtlasClient(addr) as c:
            _register(c, "mapping", MAP, "/map")
            _register(c, "chassis", ODOM, "/odom")
            c.declare_capability("chassis", TWIST_IN, "ros2", "/cmd_vel")
            bindings = {"map": Binding("map", "/map", "latched", "mapping", MAP),
                        "odom": Binding("odom", "/odom", "reliable", "chassis", ODOM),
                        "cmd_vel": Binding("cmd_vel", "/cmd_vel", "reliable", "chassis", TWIST_IN)}
            watch = UpstreamWatch(c, "nav2", bindings)
            assert watch.poll() == ({}, {})

            c.set_state("mapping", "terminated")
            terminated, rebinds = watch.poll()
            assert terminated == {"map": "the atlas reports mapping TERMINATED"}
            assert rebinds == {}

            c.unregister("mapping")                       # gone from the atlas: not lost by itself
            assert watch.poll() == ({}, {})

            _register(c, "mapping", MAP, "/map_restarted")  # a restarted provider, another topic
            terminated, rebinds = watch.poll()
            assert terminated == {}
            assert rebinds["map"].topic == "/map_restarted"
            assert rebinds["map"].provider_id == "mapping"
            bindings["map"] = rebinds["map"]               # what Inputs.rebind does
            assert watch.poll() == ({}, {})

            c.unregister("chassis")                       # the chassis restarted: commands go to its new topic
            _register(c, "chassis", ODOM, "/odom")
            c.declare_capability("chassis", TWIST_IN, "ros2", "/chassis2/cmd_vel")
            terminated, rebinds = watch.poll()
            assert set(rebinds) == {"cmd_vel"}
            assert rebinds["cmd_vel"].topic == "/chassis2/cmd_vel"
            assert rebinds["cmd_vel"].role == "cmd_vel"
            assert rebinds["cmd_vel"].contract_id == TWIST_IN
    finally:
        server.stop()
