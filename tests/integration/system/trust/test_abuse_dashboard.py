"""Issue 37 item 3: the dashboard over loopback HTTP/WebSocket. Before the fix any web page could drive
the robot (a ``text/plain`` POST from a foreign Origin is a CORS simple request), ``Host: evil.example``
(DNS rebinding) was answered, a foreign-Origin WebSocket got the live map, and any local user without a
key could send goals. Refusals here come from the guard, never from the handler (which, without an
atlas, would answer "no atlas address")."""

from __future__ import annotations

import http.client
import json
from collections.abc import Iterator
from typing import Any
from urllib.parse import parse_qs, urlsplit

import pytest

from rbnx.dashboard.launch import start_background

pytestmark = pytest.mark.integration
GOAL = b'{"x": 1.0, "y": 2.0}'
REACHED = "no atlas address"  # what the goal handler answers here: the request got past the guard


class Dash:
    """The running dashboard as a client sees it: the printed URL, its port and the key it carries."""

    def __init__(self, server: Any) -> None:
        self.url = server.url
        parts = urlsplit(self.url)
        self.port = parts.port
        self.key = parse_qs(parts.query).get("token", ["nokey"])[0]  # before the fix: no key at all


@pytest.fixture(scope="module")
def dash() -> Iterator[Dash]:
    server = start_background("", 0)
    try:
        yield Dash(server)
    finally:
        server.stop()


def _req(dash: Any, method: str, path: str, body: bytes | None = None, **headers: str) -> tuple[int, str, Any]:
    conn = http.client.HTTPConnection("127.0.0.1", dash.port, timeout=30)
    try:
        conn.request(method, path, body=body, headers={k.replace("_", "-"): v for k, v in headers.items()})
        resp = conn.getresponse()
        return resp.status, resp.read().decode("utf-8", "replace"), resp
    finally:
        conn.close()


def _cookie(dash: Any) -> str:
    """The cookie the printed URL sets ("" when no key was printed: the unfixed dashboard)."""
    if dash.key == "nokey":
        return ""
    status, _, resp = _req(dash, "GET", "/?token=" + dash.key)
    assert status == 303, status
    set_cookie = resp.getheader("set-cookie")
    assert "HttpOnly" in set_cookie, set_cookie
    assert "SameSite=Strict" in set_cookie, set_cookie
    assert resp.getheader("location") == "/"
    return set_cookie.split(";")[0]


@pytest.mark.parametrize("path", ["/api/goal", "/api/lifecycle", "/api/cancel"])
def test_cross_site_simple_requests_are_refused(dash: Any, path: str) -> None:
    body = b'{"provider": "nav2", "command": "deactivate"}' if path == "/api/lifecycle" else GOAL
    cookie = _cookie(dash)  # even the key holder's browser: a foreign page must not ride on its cookie
    status, text, _ = _req(dash, "POST", path, body, Origin="http://evil.example", Content_Type="text/plain",
                           Cookie=cookie)
    assert status in (400, 403), (status, text)
    assert REACHED not in text, text
    status, text, _ = _req(dash, "POST", path, body, Origin="http://evil.example",
                           Content_Type="application/json", Cookie=cookie)
    assert status == 403, (status, text)
    status, text, _ = _req(dash, "POST", path, body, Content_Type="text/plain", Cookie=cookie)
    assert status == 400, (status, text)
    assert "Content-Type" in text, text


def test_dns_rebinding_host_is_refused(dash: Any) -> None:
    for path in ("/", "/app.js", "/api/map.png"):
        status, text, _ = _req(dash, "GET", path, Host="evil.example")
        assert status == 421, (path, status, text)
    status, text, _ = _req(dash, "POST", "/api/goal", GOAL, Host=f"evil.example:{dash.port}",
                           Content_Type="application/json", Authorization=f"Bearer {dash.key}")
    assert status == 421, (status, text)


def test_no_key_no_driving_and_the_printed_url_grants_it(dash: Any) -> None:
    assert dash.url == f"http://127.0.0.1:{dash.port}/?token={dash.key}"
    status, text, _ = _req(dash, "POST", "/api/goal", GOAL, Content_Type="application/json")
    assert status == 401, (status, text)
    assert "rbnx dashboard" in text, text
    status, _, _ = _req(dash, "GET", "/")
    assert status == 401
    status, _, _ = _req(dash, "GET", "/?token=wrong")
    assert status == 403
    status, _, _ = _req(dash, "POST", "/api/goal", GOAL, Content_Type="application/json",
                        Authorization="Bearer wrong")
    assert status == 401
    cookie = _cookie(dash)
    status, text, _ = _req(dash, "GET", "/", Cookie=cookie)
    assert status == 200
    assert '<canvas id="map"' in text
    status, text, _ = _req(dash, "POST", "/api/goal", GOAL, Content_Type="application/json", Cookie=cookie,
                           Origin=f"http://127.0.0.1:{dash.port}")
    assert (status, REACHED in text) == (400, True), (status, text)  # past the guard
    status, text, _ = _req(dash, "POST", "/api/goal", b'{"x": NaN, "y": 1e999}', Content_Type="application/json",
                           Cookie=cookie)
    assert status == 400
    assert json.loads(text)["error"].startswith("x: must be a finite number"), text


def test_websocket_checks_origin_and_key(dash: Any) -> None:
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    ws_url = f"ws://127.0.0.1:{dash.port}/ws"
    cookie = _cookie(dash)
    for origin, headers in (("http://evil.example", {"Cookie": cookie}),
                            (f"http://127.0.0.1:{dash.port + 1}", {"Cookie": cookie}),  # another local site
                            (f"http://127.0.0.1:{dash.port}", {})):                    # no key
        with pytest.raises(InvalidStatus), connect(ws_url, origin=origin, additional_headers=headers,
                                                   open_timeout=30) as ws:
            ws.recv(timeout=5)
    with connect(ws_url, origin=f"http://127.0.0.1:{dash.port}", additional_headers={"Cookie": cookie},
                 open_timeout=30) as ws:
        assert "providers" in json.loads(ws.recv(timeout=30))
