"""MCP sessions are bounded: a real provider's MCP server under a flood of 3000 ``initialize`` calls
admits at most its session cap (the rest answer 503), its memory after the flood stays within 10 % of
before, and idle sessions expire so new clients get in again."""

from __future__ import annotations

import http.client
import json
from collections.abc import Callable
from pathlib import Path
from urllib.parse import urlsplit

import pytest
from support.procs import SLAM, Proc, wait_until

from robonix_api.mcp_server import DEFAULT_MAX_SESSIONS

pytestmark = pytest.mark.integration
TOOL = "robonix/service/map/get_mode"
INIT = json.dumps({"jsonrpc": "2.0", "id": 1, "method": "initialize",
                   "params": {"protocolVersion": "2025-06-18", "capabilities": {},
                              "clientInfo": {"name": "flood", "version": "1"}}}).encode()  # one send(): no Nagle wait


class McpHttp:
    """Raw streamable-HTTP ``initialize`` requests, one connection each (what a flooding client sends;
    a fresh connection also avoids a delayed-ACK stall of ~40 ms per request on a kept-alive one)."""

    def __init__(self, url: str) -> None:
        parts = urlsplit(url)
        self.host, self.port, self.path = parts.hostname or "127.0.0.1", parts.port or 80, parts.path

    def initialize(self) -> tuple[int, str]:
        """(HTTP status, session id or "")."""
        conn = http.client.HTTPConnection(self.host, self.port, timeout=60)
        try:
            conn.request("POST", self.path, body=INIT, headers={
                "Content-Type": "application/json", "Accept": "application/json, text/event-stream",
                "Host": f"127.0.0.1:{self.port}"})
            resp = conn.getresponse()
            resp.read()
            return resp.status, resp.getheader("mcp-session-id") or ""
        finally:
            conn.close()


def _rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError(f"no VmRSS for pid {pid}")


def _mcp_url(p: Proc) -> str:
    return wait_until(lambda: p.endpoint(TOOL, "mcp"), 60, f"{p.name} to declare its MCP tools", 0.2)


def test_initialize_flood_is_capped_and_memory_returns(procs: Callable[..., Proc]) -> None:
    slam = procs(SLAM, "mapping_flood", ROBONIX_MCP_PRELOAD_S="0")
    client = McpHttp(_mcp_url(slam))
    # warm up: the stack loaded and the first sessions' code paths run, then the baseline
    assert client.initialize()[0] == 200
    warm = [client.initialize() for _ in range(20)]
    assert all(status == 200 and sid for status, sid in warm), warm
    before = _rss_kb(slam.proc.pid)
    statuses: dict[int, int] = {}
    for _ in range(3000):
        status, _ = client.initialize()
        statuses[status] = statuses.get(status, 0) + 1
    after = _rss_kb(slam.proc.pid)
    print(f"3000 initialize calls: {statuses}; RSS {before / 1024:.1f} -> {after / 1024:.1f} MiB")
    # 21 sessions were open before: the cap of 100 admits 79 more, the rest are refused
    assert statuses == {200: DEFAULT_MAX_SESSIONS - 21, 503: 3000 - (DEFAULT_MAX_SESSIONS - 21)}, statuses
    assert after <= before * 1.10, (before, after)
    assert slam.proc.poll() is None


def test_idle_sessions_expire_and_free_their_slot(procs: Callable[..., Proc]) -> None:
    slam = procs(SLAM, "mapping_idle", ROBONIX_MCP_PRELOAD_S="0", ROBONIX_MCP_SESSION_IDLE_S="2",
                 ROBONIX_MCP_MAX_SESSIONS="3")
    client = McpHttp(_mcp_url(slam))
    opened = [client.initialize() for _ in range(3)]
    assert all(status == 200 for status, _ in opened), opened
    assert client.initialize()[0] == 503  # the cap
    # no request on those sessions: after the idle timeout they close and a new client gets in
    wait_until(lambda: client.initialize()[0] == 200, 60, "an idle session to expire", 0.5)
    assert slam.proc.poll() is None
