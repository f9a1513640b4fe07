"""A late Foxglove client against a running `rbnx boot --foxglove PORT` (issue 38's acceptance).

    python bench/foxglove_late_client.py ws://127.0.0.1:8766 [--late 5] [--subprotocol foxglove.websocket.v1]

A plain ``websockets`` client speaking the Foxglove WebSocket protocol: prints the serverInfo, the channels
advertised (topic, schema name, encoding), then, ``--late`` seconds after connecting, subscribes to /map,
/tf_static, /scan and /tf and prints how long each took to deliver its first message; /map and /tf_static
are decoded with rosbags' own message definitions. Exit 1 if /map took longer than 5 s.
"""

from __future__ import annotations

import argparse
import json
import struct
import sys
import time

from websockets.sync.client import connect

TOPICS = ("/map", "/tf_static", "/scan", "/tf")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("url")
    ap.add_argument("--late", type=float, default=5.0, help="seconds between connecting and subscribing")
    ap.add_argument("--subprotocol", default="foxglove.websocket.v1")
    args = ap.parse_args()
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    channels: dict[str, dict] = {}
    first: dict[int, tuple[float, bytes]] = {}
    with connect(args.url, subprotocols=[args.subprotocol], open_timeout=10, max_size=None) as ws:  # type: ignore[list-item]
        t0 = time.monotonic()
        subscribed_at = None
        while time.monotonic() - t0 < args.late + 10:
            try:
                frame = ws.recv(timeout=0.2)
            except TimeoutError:
                frame = None
            if isinstance(frame, str):
                op = json.loads(frame)
                if op["op"] == "serverInfo":
                    print(f"serverInfo: name={op.get('name')} capabilities={op.get('capabilities')}")
                elif op["op"] == "advertise":
                    channels.update({c["topic"]: c for c in op["channels"]})
            elif isinstance(frame, bytes) and frame[0] == 1:
                sub = struct.unpack_from("<I", frame, 1)[0]
                first.setdefault(sub, (time.monotonic(), frame[13:]))
            if subscribed_at is None and time.monotonic() - t0 >= args.late:
                print("channels:", ", ".join(f"{t} ({c['schemaName']}, {c['encoding']})"
                                             for t, c in sorted(channels.items())))
                subs = [{"id": i, "channelId": channels[t]["id"]} for i, t in enumerate(TOPICS) if t in channels]
                ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                subscribed_at = time.monotonic()
            if subscribed_at is not None and len(first) == len(TOPICS):
                break
    result = {}
    for i, t in enumerate(TOPICS):
        if i in first and subscribed_at is not None:
            result[t] = round(first[i][0] - subscribed_at, 3)
    print("first message after subscribing (s):", result)
    if 0 in first:
        grid = store.deserialize_cdr(first[0][1], "nav_msgs/msg/OccupancyGrid")
        print(f"/map decoded with rosbags: {grid.info.width}x{grid.info.height} @ {grid.info.resolution:.3f} m, "
              f"frame {grid.header.frame_id}")
    if 1 in first:
        tfs = store.deserialize_cdr(first[1][1], "tf2_msgs/msg/TFMessage")
        print("/tf_static:", [f"{t.header.frame_id}->{t.child_frame_id}" for t in tfs.transforms])
    return 0 if result.get("/map", 99) <= 5.0 else 1


if __name__ == "__main__":
    sys.exit(main())
