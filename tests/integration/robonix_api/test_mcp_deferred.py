"""The MCP server stack loads on the first client or after the preload time, never before it is needed,
and the tools are on the atlas (with their schemas) before it loads. Real atlas, real official client."""

from __future__ import annotations

import asyncio
import socket
import subprocess
import sys

import pytest
from support.procs import wait_until

from robonix_api import Service
from robonix_api.atlas_client import AtlasClient
from robonix_api.mcp_deferred import DeferredMcpServer, preload_delay
from robonix_api.proto_gen import navigation_pb2

pytestmark = pytest.mark.integration

NAV = "robonix/service/navigation/navigate"


def test_first_client_loads_the_stack(atlas_server, short_heartbeat, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from mcp import Client

    monkeypatch.setenv("ROBONIX_MCP_PRELOAD_S", "300")  # only a client can trigger the load here
    svc = Service("deferred_p", "robonix/test", atlas=atlas_server.address)

    @svc.mcp(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        """Go somewhere."""
        return navigation_pb2.Navigate_Response(accepted=True, run_id="r", detail=f"x={req.goal.pose.position.x}")

    svc.run_in_thread()
    try:
        server = svc._mcp_server
        assert isinstance(server, DeferredMcpServer)
        client = AtlasClient(atlas_server.address)
        try:
            (cap,) = client.find_capability(contract_id=NAV, transport="mcp")
        finally:
            client.close()
        assert '"goal"' in cap.params.input_schema_json  # declared with its schema before the stack exists
        assert not server.loaded

        async def talk():  # type: ignore[no-untyped-def]
            async with Client(svc.mcp_url) as c:
                return await c.call_tool("navigate", {"goal": {"pose": {"position": {"x": 1.5}}}})

        result = asyncio.run(asyncio.wait_for(talk(), 120))
        assert result.structured_content == {"accepted": True, "run_id": "r", "detail": "x=1.5"}
        assert server.loaded
    finally:
        svc.stop()


def test_preload_time_loads_without_a_client() -> None:
    built: list[socket.socket] = []

    class Built:
        def __init__(self, sock: socket.socket) -> None:
            built.append(sock)

        def stop(self) -> None:
            built[0].close()

    server = DeferredMcpServer("t", "127.0.0.1", Built, preload_s=0.05)
    server.start()
    assert server.wait_loaded(30)
    assert built
    assert built[0].getsockname()[1] == server.port
    server.stop()
    assert built[0].fileno() == -1


def test_stop_before_load_releases_the_port() -> None:
    calls: list[int] = []
    server = DeferredMcpServer("t", "127.0.0.1", lambda sock: calls.append(1), preload_s=300)
    port = server.start()
    server.stop()
    assert calls == []
    with socket.socket() as s:  # the port is free again
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(("127.0.0.1", port))


def test_a_failing_build_is_logged_not_raised(caplog) -> None:  # type: ignore[no-untyped-def]
    def boom(sock: socket.socket) -> None:
        raise RuntimeError("no stack")

    server = DeferredMcpServer("t", "127.0.0.1", boom, preload_s=0)
    server.start()
    wait_until(lambda: "failed to start" in caplog.text, 30, "the failure logged")
    assert not server.loaded
    server.stop()


@pytest.mark.parametrize(("raw", "ok"), [("", True), ("0", True), ("2.5", True), ("-1", False), ("1e9", False),
                                         ("soon", False)])
def test_preload_variable_is_checked(monkeypatch, raw: str, ok: bool) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("ROBONIX_MCP_PRELOAD_S", raw)
    if ok:
        assert preload_delay() >= 0
    else:
        with pytest.raises(ValueError, match="ROBONIX_MCP_PRELOAD_S"):
            preload_delay()


def test_provider_start_does_not_import_the_mcp_stack() -> None:
    """A provider process registers, serves its Driver and declares its MCP tools without ``mcp``."""
    code = (
        "import sys\n"
        "from robonix_api.mcp_deferred import DeferredMcpServer\n"
        "from robonix_api.mcp_tools import tool_shape\n"
        "import slam_service.provider, hal_panda_mobile.provider\n"
        "print(sorted(m for m in ('mcp', 'uvicorn', 'starlette', 'scipy') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == "[]"
