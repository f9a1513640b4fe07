"""The live Foxglove bridge over real DDS, checked with a plain ``websockets`` client speaking the Foxglove
WebSocket protocol (subprotocol foxglove.websocket.v1) and rosbags' own message definitions: serverInfo,
channels for topics found by discovery with their ros2msg schemas, and latched /map and /tf_static reaching
a client that subscribes long after they were published."""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import time
from typing import Any

import pytest
from support.procs import wait_until
from websockets.sync.client import ClientConnection, connect

from rbnx.foxglove_live import FoxgloveBridge
from robonix_api.dds import DdsNode, LaserScan, MapMetaData, OccupancyGrid, Odometry, TFMessage, Time
from robonix_api.dds.tf import make_transform

pytestmark = pytest.mark.timeout(120)


def _map() -> OccupancyGrid:
    g = OccupancyGrid(info=MapMetaData(resolution=0.05, width=40, height=30))
    g.header.frame_id, g.header.stamp = "map", Time.from_sec(5.0)
    g.data = [100 if i % 7 == 0 else 0 for i in range(40 * 30)]
    return g


class _Client:
    """A Foxglove WebSocket client: JSON ops in, binary messageData (op 1) out."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.ops: list[dict[str, Any]] = []
        self.channels: dict[str, dict[str, Any]] = {}
        self.data: dict[int, list[tuple[int, bytes]]] = {}  # subscription id -> (timestamp, payload)

    def pump(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            try:
                frame = self.ws.recv(timeout=left)
            except TimeoutError:
                return
            if isinstance(frame, bytes):
                assert frame[0] == 1, f"binary opcode {frame[0]}"
                sub, ts = struct.unpack_from("<IQ", frame, 1)
                self.data.setdefault(sub, []).append((ts, frame[13:]))
            else:
                op = json.loads(frame)
                self.ops.append(op)
                if op["op"] == "advertise":
                    self.channels.update({c["topic"]: c for c in op["channels"]})

    def wait_for(self, pred: Any, seconds: float, what: str) -> float:
        t0 = time.monotonic()
        while not pred():
            assert time.monotonic() - t0 < seconds, what
            self.pump(0.1)
        return time.monotonic() - t0

    def subscribe(self, sub_id: int, topic: str) -> None:
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": sub_id, "channelId": self.channels[topic]["id"]}]}))


def test_late_client_gets_channels_schemas_and_latched_map() -> None:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with DdsNode(name="robot") as node:
        map_pub = node.create_publisher("/map", OccupancyGrid, "latched")
        static = node.create_publisher("/tf_static", TFMessage, "latched")
        scan = node.create_publisher("/scan", LaserScan, "best_effort")
        tf = node.create_publisher("/tf", TFMessage, "reliable")
        map_pub.publish(_map())
        static.publish(TFMessage(transforms=[make_transform("base_link", "laser", 0.1, 0.0, 0.0, 5.0)]))
        bridge = FoxgloveBridge(0)
        bridge.start()
        try:
            assert bridge.url == f"ws://127.0.0.1:{bridge.port}"
            assert bridge.port > 0
            with connect(bridge.url, subprotocols=["foxglove.websocket.v1"], open_timeout=10) as ws:  # type: ignore[list-item]
                assert ws.subprotocol == "foxglove.websocket.v1"
                c = _Client(ws)
                c.wait_for(lambda: {"/map", "/scan", "/tf", "/tf_static"} <= set(c.channels), 30,
                           "channels for /map /scan /tf /tf_static")
                assert c.ops[0]["op"] == "serverInfo"
                ch = c.channels["/map"]
                assert (ch["encoding"], ch["schemaName"], ch["schemaEncoding"]) == (
                    "cdr", "nav_msgs/msg/OccupancyGrid", "ros2msg")
                assert ch["schema"].startswith("std_msgs/Header header\n")
                # the map was published before the bridge existed; subscribe late, well after discovery
                wait_until(lambda: bridge.held_latched("/map") == 1, 20, "bridge holds the latched map")
                c.pump(1.0)
                c.subscribe(1, "/map")
                c.subscribe(2, "/tf_static")
                took = c.wait_for(lambda: 1 in c.data and 2 in c.data, 5.0, "latched /map and /tf_static")
                assert took < 5.0
                grid = store.deserialize_cdr(c.data[1][0][1], "nav_msgs/msg/OccupancyGrid")
                assert (grid.info.width, grid.info.height, grid.header.frame_id) == (40, 30, "map")
                assert list(grid.data) == _map().data
                tfs = store.deserialize_cdr(c.data[2][0][1], "tf2_msgs/msg/TFMessage")
                assert tfs.transforms[0].child_frame_id == "laser"
                # a writer that comes and goes (its disposed discovery sample has no topic name) is harmless
                gone = node.create_publisher("/transient_odom", Odometry, "reliable")
                c.wait_for(lambda: "/transient_odom" in c.channels, 30, "the new topic's channel")
                gone.close()
                c.pump(1.0)
                # live topics flow too, with receive times as timestamps
                c.subscribe(3, "/tf")
                sample = TFMessage(transforms=[make_transform("odom", "base_link", 1.0, 2.0, 0.0, 6.0)])
                sent = [0.0]

                def tf_arrived() -> bool:
                    # /tf is volatile, as a live TF stream is: a sample published before the bridge has acted
                    # on the subscribe is not for this client, so publish at a rate until one arrives
                    if 3 in c.data:
                        return True
                    if time.monotonic() - sent[0] > 0.5:
                        tf.publish(sample)
                        sent[0] = time.monotonic()
                    return False

                c.wait_for(tf_arrived, 30, "/tf sample")
                got = store.deserialize_cdr(c.data[3][0][1], "tf2_msgs/msg/TFMessage")
                assert got.transforms[0].transform.translation.y == 2.0
                assert abs(c.data[3][0][0] - time.time_ns()) < 60e9
            # the SDK's own name of the protocol works as well
            with connect(bridge.url, subprotocols=["foxglove.sdk.v1"], open_timeout=10) as ws:  # type: ignore[list-item]
                c2 = _Client(ws)
                c2.wait_for(lambda: "/map" in c2.channels, 30, "channels on the second client")
                c2.subscribe(7, "/map")
                c2.wait_for(lambda: 7 in c2.data, 5.0, "latched /map on the second client")
            del scan
        finally:
            bridge.stop()


def test_boot_foxglove_port_errors_are_one_line_exit_2(tmp_path: Any) -> None:
    r = subprocess.run([sys.executable, "-m", "rbnx.cli", "boot", "--foxglove", "70000", "-f", "missing.yaml"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert r.stderr.strip() == "rbnx boot: --foxglove: port must be 0..65535, got 70000"
