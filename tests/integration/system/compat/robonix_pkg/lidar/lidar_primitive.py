"""A lidar Primitive that uses only robonix-api 0.1.0rc1's documented API (no robonix-nav names).

It publishes a synthetic scan of a round room while ACTIVE. The message class comes from
``robonix_api.ros.resolve_msg_type`` so the file imports nothing ROS-specific itself.
"""

import math
import threading

from robonix_api import Err, Ok, Primitive
from robonix_api.ros import resolve_msg_type

LIDAR = "robonix/primitive/lidar/lidar"

lidar = Primitive(id="compat_lidar", namespace="robonix/primitive/lidar")
settings = {}
stopped = threading.Event()


@lidar.on_init
def init(cfg: dict):
    rate = float(cfg.get("rate_hz", 10.0))
    beams = int(cfg.get("beams", 360))
    if rate <= 0:
        return Err("rate_hz: must be > 0")
    if beams < 3:
        return Err("beams: must be >= 3")
    settings.update(rate=rate, beams=beams)
    lidar.create_publisher(contract_id=LIDAR, topic=cfg.get("topic", "/scan"), msg_type="LaserScan")
    return Ok()


def publish_scans():
    scan_cls = resolve_msg_type("sensor_msgs/msg/LaserScan")
    beams = settings["beams"]
    while not stopped.wait(1.0 / settings["rate"]):
        msg = scan_cls()
        msg.header.frame_id = "laser"
        msg.angle_min = -math.pi
        msg.angle_increment = 2.0 * math.pi / beams
        msg.angle_max = msg.angle_min + msg.angle_increment * (beams - 1)
        msg.range_min = 0.05
        msg.range_max = 10.0
        msg.scan_time = 1.0 / settings["rate"]
        msg.ranges = [2.0] * beams
        lidar.emit(LIDAR, msg)


@lidar.on_activate
def activate():
    stopped.clear()
    threading.Thread(target=publish_scans, name="scan-publisher", daemon=True).start()
    return Ok()


@lidar.on_deactivate
def deactivate():
    stopped.set()
    return Ok()


@lidar.on_shutdown
def shutdown():
    stopped.set()
    return Ok()


if __name__ == "__main__":
    lidar.run()
