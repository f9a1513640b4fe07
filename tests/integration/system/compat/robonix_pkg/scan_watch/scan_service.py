"""A Service that uses only robonix-api 0.1.0rc1's documented API (no robonix-nav names).

CMD_INIT answers Deferred until a lidar provider is on the atlas, then subscribes to it through a
channel. One contract is served over gRPC (``@provides_grpc``), one as an MCP tool (``@provides_mcp``).
The generated proto modules are imported by their top-level names, as robonix's codegen lays them out.
"""

import threading

from robonix_api import ATLAS, Deferred, Ok, Service, Transport

# isort: split
# robonix-api puts the package's generated protos on sys.path when it is imported, so they come after it.
import map_pb2

LIDAR = "robonix/primitive/lidar/lidar"

svc = Service(id="compat_scan_watch", namespace="robonix/service/map")
lock = threading.Lock()
seen = {"count": 0, "mean_range": 0.0, "frame_id": "", "min_scans": 1}


def on_scan(msg):
    ranges = list(msg.ranges)
    with lock:
        seen["count"] += 1
        seen["mean_range"] = sum(ranges) / len(ranges) if ranges else 0.0
        seen["frame_id"] = msg.header.frame_id


@svc.on_init
def init(cfg: dict):
    seen["min_scans"] = int(cfg.get("min_scans", 1))
    caps = ATLAS.find_capability(contract_id=LIDAR, transport=Transport.ROS2)
    if not caps:
        return Deferred(f"waiting for {LIDAR}")
    channel = svc.connect_capability(caps[0], LIDAR, Transport.ROS2)
    svc.create_subscription_from_channel(channel, msg_type="LaserScan", callback=on_scan)
    return Ok()


@svc.provides_grpc("robonix/service/map/get_mode")
def get_mode(request):
    """Always 'watching'; the detail counts the scans received."""
    with lock:
        count = seen["count"]
    return map_pb2.GetMode_Response(ok=True, mode="watching", detail=f"{count} scans")


@svc.provides_mcp("robonix/service/map/get_pose")
def get_pose(request: map_pb2.GetPose_Request) -> map_pb2.GetPose_Response:
    """Mean range of the last lidar scan (as x) and its frame."""
    with lock:
        ready = seen["count"] >= seen["min_scans"]
        return map_pb2.GetPose_Response(ok=ready, x=seen["mean_range"], frame_id=seen["frame_id"],
                                        detail=f"{seen['count']} scans")


if __name__ == "__main__":
    svc.run()
