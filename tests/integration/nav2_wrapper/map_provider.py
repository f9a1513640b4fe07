"""A stand-in MAP provider for the navigation tests (until the SLAM provider exists).

``python tests/nav_provider/map_provider.py``: a robonix ``Service`` that declares
``robonix/service/map/occupancy_grid`` on /map ("transient_local") from process start; on CMD_INIT it
publishes the scene's ground-truth grid once (latched, so late joiners get it) and then keeps the
map→odom identity on /tf, stamped with sim time, as a SLAM provider would (the HAL's odom frame
coincides with its world frame). Config: {scene, resolution, map_topic}.
"""

from __future__ import annotations

import logging
import os
import sys
import threading
from typing import Any

from hal_panda_mobile.files import load_robot_description, load_scene
from hal_panda_mobile.sim.raster import rasterize
from robonix_api import Err, Ok, Service
from robonix_api.dds import Clock, OccupancyGrid, TfBroadcaster
from robonix_api.dds.convert import grid_to_msg

MAP = "robonix/service/map/occupancy_grid"
TF_PERIOD = 0.05  # sim s between map->odom transforms


class MapStandIn:
    def __init__(self, svc: Service) -> None:
        self.svc = svc
        self.topic = svc.declare_ros2_topic(MAP, os.environ.get("TEST_MAP_TOPIC", "/map"), qos="transient_local")
        self.clock_sub: Any = None
        self.tf: TfBroadcaster | None = None
        self._last = -1.0
        self._lock = threading.Lock()
        svc.on_init(self.on_init)
        svc.on_shutdown(self.on_shutdown)

    def on_init(self, cfg: dict[str, Any]) -> Ok | Err:
        try:
            scene = load_scene(cfg.get("scene", "apartment"), robot=load_robot_description(None))
            grid = rasterize(scene.obstacles(), scene.bounds, float(cfg.get("resolution", 0.05)))
        except Exception as exc:
            return Err(f"scene: {exc}")
        node = self.svc.dds_node()
        pub = node.create_publisher(self.topic, OccupancyGrid, "transient_local")
        pub.publish(grid_to_msg(grid, 0.0, "map"))
        self._pub = pub
        self.tf = TfBroadcaster(node)
        self.clock_sub = node.create_subscription("/clock", Clock, self._on_clock, "clock")
        return Ok()

    def _on_clock(self, msg: Any) -> None:
        assert self.tf is not None
        t = msg.clock.to_sec()
        with self._lock:
            if t - self._last < TF_PERIOD and t >= self._last:
                return
            self._last = t
        self.tf.send("map", "odom", 0.0, 0.0, 0.0, t)

    def on_shutdown(self) -> Ok:
        for item in (self.clock_sub, self.tf):
            if item is not None:
                item.close()
        return Ok()


def main() -> int:
    logging.basicConfig(level="INFO", format="%(asctime)s %(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    svc = Service(os.environ.get("RBNX_INSTANCE_NAME") or "test_map", "robonix/service/map")
    MapStandIn(svc)
    svc.run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
