"""Issue 37 abuse cases on the MCP gateway, over loopback HTTP against a real Gateway, a real atlas and a
real in-process provider:

* item 5: ``NaN``, ``Infinity`` and ``1e999`` in tool arguments were forwarded as ``null`` and became 0
  (``nav2.navigate`` accepted a goal at x = 0); now the gateway (and a provider's own MCP server) refuses
  them naming the field, and the provider never sees the call;
* item 9: unauthenticated ``initialize`` calls filled the session limit and the token holder then got HTTP
  503; now anonymous clients have their own small quota and the token holder still gets in.
"""

from __future__ import annotations

import http.client
import json
from collections.abc import Iterator
from typing import Any
from urllib.parse import urlsplit

import pytest
from support.procs import wait_until

from rbnx.gateway import Entry, Gateway, LifecycleControl
from robonix_api import Ok, Service
from robonix_api.auth import TOKEN_ENV
from robonix_api.proto_gen import navigation_pb2

from .conftest import TOKEN

pytestmark = pytest.mark.integration
NAV = "robonix/service/navigation/navigate"
PROTOCOL = "2025-06-18"


class RawMcp:
    """Hand-written streamable-HTTP requests: the JSON text goes on the wire as written (``NaN`` too)."""

    def __init__(self, url: str, token: str | None) -> None:
        parts = urlsplit(url)
        self.port, self.path = parts.port or 80, parts.path
        self.token = token
        self.session = ""

    def post(self, body: str) -> tuple[int, Any, str]:
        """(status, the JSON-RPC reply or None, the session id the server gave)."""
        headers = {"Content-Type": "application/json", "Accept": "application/json, text/event-stream",
                   "Host": f"127.0.0.1:{self.port}", "MCP-Protocol-Version": PROTOCOL}
        if self.token:
            headers["Authorization"] = f"Bearer {self.token}"
        if self.session:
            headers["Mcp-Session-Id"] = self.session
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
        try:
            conn.request("POST", self.path, body=body.encode(), headers=headers)
            resp = conn.getresponse()
            text = resp.read().decode("utf-8", "replace")
            sid = resp.getheader("mcp-session-id") or ""
        finally:
            conn.close()
        data = [line[5:].strip() for line in text.splitlines() if line.startswith("data:")]
        reply = json.loads(data[-1]) if data else (json.loads(text) if text.strip().startswith("{") else None)
        return resp.status, reply, sid

    def initialize(self) -> int:
        status, _, sid = self.post(json.dumps({"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {
            "protocolVersion": PROTOCOL, "capabilities": {}, "clientInfo": {"name": "abuse", "version": "1"}}}))
        if status == 200:
            self.session = sid
            self.post('{"jsonrpc": "2.0", "method": "notifications/initialized"}')
        return status

    def call(self, name: str, arguments_json: str) -> dict[str, Any]:
        status, reply, _ = self.post('{"jsonrpc": "2.0", "id": 2, "method": "tools/call", "params": '
                                     f'{{"name": "{name}", "arguments": {arguments_json}}}}}')
        assert status == 200, (status, reply)
        return reply["result"]


@pytest.fixture
def token(monkeypatch: pytest.MonkeyPatch) -> str:
    monkeypatch.setenv(TOKEN_ENV, TOKEN)
    return TOKEN


@pytest.fixture
def goals(atlas: str, token: str) -> Iterator[list[float]]:
    """A provider whose navigate tool records the goal x it was given."""
    seen: list[float] = []
    svc = Service("abuse_nav", "robonix/service/navigation", atlas=atlas)
    svc.on_init(lambda _cfg: Ok())

    @svc.mcp(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        """Send the robot to a goal."""
        seen.append(req.goal.pose.position.x)
        return navigation_pb2.Navigate_Response(accepted=True, run_id="r1",
                                                detail=f"goal ({req.goal.pose.position.x:.2f}, "
                                                       f"{req.goal.pose.position.y:.2f}) accepted")

    svc.run_in_thread()
    try:
        yield seen
    finally:
        svc.stop()


def _gateway(atlas: str) -> Gateway:
    gw = Gateway(atlas, LifecycleControl(atlas, [Entry("abuse_nav", "service", {})], driver_timeout=30.0,
                                         shutdown_all=lambda: None), poll_s=0.2)
    gw.start()
    return gw


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity", "1e999"])
def test_non_finite_tool_arguments_are_refused_naming_the_field(atlas: str, goals: list[float], token: str,
                                                                literal: str) -> None:
    gw = _gateway(atlas)
    try:
        wait_until(lambda: "abuse_nav.navigate" in {t.name for t in gw._tools.values()}, 60,
                   "the gateway to list the provider's tool")
        client = RawMcp(gw.url, token)
        assert client.initialize() == 200
        ok = client.call("abuse_nav.navigate", '{"goal": {"pose": {"position": {"x": 1.25, "y": 1.5}}}}')
        assert not ok.get("isError"), ok
        assert goals == [1.25]
        bad = client.call("abuse_nav.navigate", f'{{"goal": {{"pose": {{"position": {{"x": {literal}, "y": 1.5}}}}}}}}')
        text = "".join(c.get("text", "") for c in bad["content"])
        assert bad.get("isError"), bad
        assert "goal.pose.position.x: must be a finite number" in text, text
        assert goals == [1.25], "the provider must not have been called with the non-finite goal"
    finally:
        gw.stop()


def test_anonymous_initialize_flood_does_not_lock_out_the_token_holder(atlas: str, token: str,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROBONIX_MCP_MAX_SESSIONS", "10")
    monkeypatch.setenv("ROBONIX_MCP_MAX_ANON_SESSIONS", "4")
    gw = _gateway(atlas)
    try:
        anon = [RawMcp(gw.url, None).initialize() for _ in range(30)]
        holder = [RawMcp(gw.url, token).initialize() for _ in range(10)]
        assert holder == [200] * 10, holder  # the token holder still gets in, up to the full cap ...
        assert anon.count(200) <= 4, anon  # ... anonymous clients had their own small quota
        assert anon.count(503) >= 26, anon
        assert RawMcp(gw.url, token).initialize() == 503  # and the holder's own cap still bounds memory
        wrong = [RawMcp(gw.url, "not-the-token").initialize() for _ in range(3)]
        assert wrong == [503] * 3, wrong  # a wrong token counts as anonymous
    finally:
        gw.stop()
