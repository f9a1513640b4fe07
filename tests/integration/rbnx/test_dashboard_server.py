"""The dashboard server over real HTTP/WebSocket and DDS, without a robot: bad requests get HTTP 400 naming
the field, the map PNG is north-up with walls black / free white / unknown grey and is served only once a
/map arrived, and the WebSocket pushes snapshots carrying the TF pose."""

from __future__ import annotations

import io
import json
import urllib.error
import urllib.request
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from support.browser import free_port
from support.procs import wait_until

from rbnx.dashboard.launch import start_background
from robonix_api.dds import DdsNode, OccupancyGrid, StaticTfBroadcaster, TfBroadcaster
from robonix_api.dds.convert import header

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def dash() -> Iterator[Any]:
    server = start_background("", free_port())  # no atlas: control-plane calls must fail cleanly
    yield server
    server.stop()


def _auth(dash: Any) -> dict[str, str]:
    return {"Authorization": f"Bearer {dash.key}"}


def _get(dash: Any, path: str) -> Any:
    return urllib.request.urlopen(urllib.request.Request(dash.base_url + path, headers=_auth(dash)), timeout=30)


def _post(dash: Any, path: str, body: bytes) -> tuple[int, dict[str, Any]]:
    req = urllib.request.Request(dash.base_url + path, data=body, method="POST",
                                 headers={"Content-Type": "application/json", **_auth(dash)})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


@pytest.mark.parametrize(("path", "body", "message"), [
    ("api/goal", b"{}", "x: required"),
    ("api/goal", b'{"x": "a", "y": 1}', "x: must be a finite number"),
    ("api/goal", b"[1, 2]", "body: must be a JSON object"),
    ("api/goal", b"not json", "body: must be a JSON object"),
    ("api/goal", b'{"x": 1, "y": 2}', "no atlas address"),
    ("api/lifecycle", b'{"command": "activate"}', "provider: required"),
    ("api/lifecycle", b'{"provider": "mapping", "command": "reboot"}', "command: must be activate or deactivate"),
])
def test_bad_requests_get_400_naming_the_field(dash: Any, path: str, body: bytes, message: str) -> None:
    status, data = _post(dash, path, body)
    assert status == 400, data
    assert message in data["error"], data


def test_page_and_map_png(dash: Any) -> None:
    from PIL import Image

    with _get(dash, "") as r:
        assert b'<canvas id="map"' in r.read()
    with _get(dash, "app.js") as r:
        assert b"new WebSocket" in r.read()
    with pytest.raises(urllib.error.HTTPError) as err:
        _get(dash, "api/map.png")
    assert err.value.code == 404

    grid = OccupancyGrid(header=header(1.0, "map"))
    grid.info.resolution, grid.info.width, grid.info.height = 0.1, 4, 3
    cells = np.full((3, 4), -1, np.int8)
    cells[0, :] = 0     # bottom row (lowest y): free
    cells[2, 3] = 100   # top-right: wall
    grid.data = cells.reshape(-1)
    with DdsNode(name="dash_map") as node:
        pub = node.create_publisher("/map", OccupancyGrid, "latched")
        pub.publish(grid)

        def png() -> bytes | None:
            try:
                with _get(dash, "api/map.png") as r:
                    return r.read()
            except urllib.error.HTTPError:
                return None

        data = wait_until(png, 30, "the map PNG")
    img = np.asarray(Image.open(io.BytesIO(data)))
    assert img.shape == (3, 4)
    assert (img[2] == 255).all(), "bottom image row = lowest y = free (white)"
    assert img[0, 3] == 0, "top-right = wall (black)"
    assert img[1, 0] == 205, "unknown = grey"


def test_websocket_pushes_the_tf_pose(dash: Any) -> None:
    from websockets.sync.client import connect

    with DdsNode(name="dash_tf") as node:
        StaticTfBroadcaster(node).send("map", "odom", 1.0, 0.0, 0.0)
        tf = TfBroadcaster(node)
        with connect(dash.base_url.replace("http", "ws") + "ws", open_timeout=30,
                     additional_headers=_auth(dash)) as ws:
            def pose() -> dict[str, float] | None:
                tf.send("odom", "base_link", 0.5, 0.25, 0.0, 2.0)
                snap = json.loads(ws.recv(timeout=5))
                assert {"map", "pose", "plan", "scan", "providers", "nav", "goal"} <= set(snap)
                return snap["pose"]

            p = wait_until(pose, 30, "a pose in the pushed snapshot")
    assert p["x"] == pytest.approx(1.5)
    assert p["y"] == pytest.approx(0.25)
