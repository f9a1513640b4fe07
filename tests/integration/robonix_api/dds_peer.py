"""Helper process for the cross-process tests: publishes /scan, /map, /tf, /tf_static and /clock.

Run as ``python tests/integration/robonix_api/dds_peer.py``; prints READY once publishing, MAP <checksum>
after each latched map, and exits cleanly on SIGTERM or when stdin closes. It inherits
ROS_DOMAIN_ID/CYCLONEDDS_URI from the test.
"""

from __future__ import annotations

import math
import signal
import sys
import threading

import numpy as np

from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid, StaticTfBroadcaster, TfBroadcaster
from robonix_api.dds.clock import ClockPublisher
from robonix_api.dds.convert import grid_to_msg, laser_scan
from robonix_api.dds.tf import make_transform
from robonix_common.grid import GridMap

CLOCK_START = 1000.0


def main() -> None:
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    node = DdsNode(name="peer")
    scan_pub = node.create_publisher("/scan", LaserScan, "best_effort")
    map_pub = node.create_publisher("/map", OccupancyGrid, "latched")
    tf = TfBroadcaster(node)
    static_tf = StaticTfBroadcaster(node)
    clock = ClockPublisher(node)
    static_tf.send_transform(make_transform("base_link", "laser", 0.2, 0.0, 0.0, CLOCK_START))
    # two maps: a late subscriber must get only the last one (latched = transient local, depth 1)
    for value in (10, 42):
        data = np.full((300, 400), value, dtype=np.int8)
        data[0, :5] = [-1, 0, 100, 7, -1]
        map_pub.publish(grid_to_msg(GridMap(data, 0.05, -1.0, -2.0, 0.0), CLOCK_START))
    print("READY", flush=True)
    k = 0
    while not stop.wait(0.02):
        t = CLOCK_START + k * 0.02
        clock.publish(t)
        scan_pub.publish(laser_scan(np.arange(360) * 0.01, -math.pi, 2 * math.pi / 360, range_max=12.0,
                                    stamp=t, frame_id="laser"))
        tf.send_transform([make_transform("map", "odom", 1.0, 0.0, 0.0, t),
                           make_transform("odom", "base_link", 0.01 * k, 0.0, math.pi / 2, t)])
        k += 1
    node.close()


if __name__ == "__main__":
    main()
