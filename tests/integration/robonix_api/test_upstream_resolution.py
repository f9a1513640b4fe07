"""Contract-based topic resolution (robonix_api.upstream) against a real atlas."""

from __future__ import annotations

import pytest

from atlas.server import AtlasServer
from robonix_api.atlas_client import AtlasClient
from robonix_api.types import Ros2Params
from robonix_api.upstream import MissingUpstream, resolve_topic, still_there

MAP = "robonix/service/map/occupancy_grid"


def test_resolution_pin_remap_missing_and_qos() -> None:
    with AtlasServer(listen="127.0.0.1:0") as server:
        atlas = AtlasClient(server.address)
        try:
            with pytest.raises(MissingUpstream, match=f"waiting for {MAP} \\(no provider on the atlas\\)"):
                resolve_topic(atlas, "nav2", "map", MAP, default_qos="transient_local")
            assert resolve_topic(atlas, "nav2", "scan", "robonix/primitive/lidar/lidar",
                                 default_qos="best_effort", required=False) is None
            for pid, topic in (("mapping_b", "/map_b"), ("mapping_a", "/map_a")):
                atlas.register_service(pid, "robonix/service/map")
                atlas.declare_capability(pid, MAP, topic, "ros2", Ros2Params(qos_profile="transient_local"))
            b = resolve_topic(atlas, "nav2", "map", MAP, default_qos="reliable")
            assert (b.topic, b.qos, b.provider_id, b.source) == ("/map_a", "latched", "mapping_a", "atlas")
            assert resolve_topic(atlas, "nav2", "map", MAP, default_qos="reliable", pin="mapping_b").topic == "/map_b"
            with pytest.raises(MissingUpstream, match="provider 'ghost' is not on the atlas"):
                resolve_topic(atlas, "nav2", "map", MAP, default_qos="reliable", pin="ghost")
            r = resolve_topic(atlas, "nav2", "map", MAP, default_qos="transient_local", remap="/robot/map")
            assert (r.topic, r.qos, r.source) == ("/robot/map", "latched", "topic_remap")
            assert still_there(atlas, b)
            assert still_there(atlas, r)
            atlas.unregister("mapping_a")
            assert not still_there(atlas, b)
            assert atlas.inspect().get("channels", []) == []  # lookups close their channels
        finally:
            atlas.close()
