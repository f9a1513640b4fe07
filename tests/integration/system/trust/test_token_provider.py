"""A provider under a deployment token: its Driver and state-changing contracts want the token over gRPC
and MCP, read-only contracts stay open. A real in-process provider with a real gRPC server and MCP stack."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator

import grpc
import pytest

from atlas.server import AtlasServer
from robonix_api import Ok, Service, auth
from robonix_api.auth import TOKEN_ENV
from robonix_api.proto_gen import lifecycle_pb2, navigation_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rc

from .conftest import TOKEN

NAV = "robonix/service/navigation/navigate"
STATUS = "robonix/service/navigation/navigate/status"


@pytest.fixture
def provider(token_atlas: AtlasServer, monkeypatch: pytest.MonkeyPatch) -> Iterator[Service]:
    for name in ("RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED", "ROBONIX_ADVERTISE_HOST", "ROBONIX_PROVIDER_BIND_HOST"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("ROBONIX_MCP_PRELOAD_S", "0")
    monkeypatch.setenv(TOKEN_ENV, TOKEN)
    svc = Service("nav2", "robonix/service/navigation", atlas=token_atlas.address)
    svc.on_init(lambda cfg: Ok())
    goals: list[str] = []

    @svc.grpc(NAV)
    @svc.mcp(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        goals.append(req.goal.header.frame_id)
        return navigation_pb2.Navigate_Response(accepted=True, run_id=f"run{len(goals)}")

    @svc.grpc(STATUS)
    @svc.mcp(STATUS)
    def status(req: navigation_pb2.GetNavigationStatus_Request) -> navigation_pb2.GetNavigationStatus_Response:
        return navigation_pb2.GetNavigationStatus_Response(state="IDLE")

    svc.goals = goals  # type: ignore[attr-defined]
    svc.run_in_thread()
    yield svc
    svc.stop()


def _navigate(endpoint: str, metadata: list[tuple[str, str]] | None) -> navigation_pb2.Navigate_Response:
    with grpc.insecure_channel(endpoint) as ch:
        return rc.RobonixServiceNavigationNavigateStub(ch).Navigate(navigation_pb2.Navigate_Request(), timeout=10,
                                                                    metadata=metadata)


def test_grpc_driver_and_navigate_need_the_token_status_does_not(provider: Service) -> None:
    ep = provider.grpc_endpoint
    for md, code in ((None, grpc.StatusCode.UNAUTHENTICATED),
                     ([(auth.METADATA_KEY, "x")], grpc.StatusCode.PERMISSION_DENIED)):
        with pytest.raises(grpc.RpcError) as err:
            _navigate(ep, md)
        assert err.value.code() == code
        assert "Navigate" in err.value.details()
        with grpc.insecure_channel(ep) as ch, pytest.raises(grpc.RpcError) as err:
            rc.RobonixLifecycleDriverStub(ch).Driver(lifecycle_pb2.Driver_Request(command=0), timeout=10, metadata=md)
        assert err.value.code() == code
    assert provider.goals == []  # type: ignore[attr-defined]
    assert provider.state.value != "inactive"  # the refused CMD_INIT did not run

    assert _navigate(ep, [(auth.METADATA_KEY, TOKEN)]).accepted
    with auth.channel(ep) as ch:  # the SDK's channel sends $ROBONIX_DEPLOY_TOKEN itself
        nav = rc.RobonixServiceNavigationNavigateStub(ch)
        assert nav.Navigate(navigation_pb2.Navigate_Request(), timeout=10).accepted
    with grpc.insecure_channel(ep) as ch:  # read-only: open
        st = rc.RobonixServiceNavigationNavigateStatusStub(ch).GetNavigationStatus(
            navigation_pb2.GetNavigationStatus_Request(), timeout=10)
    assert st.state == "IDLE"
    assert len(provider.goals) == 2  # type: ignore[attr-defined]


def test_mcp_navigate_needs_bearer_token_status_does_not(provider: Service) -> None:
    from mcp import Client

    async def talk() -> None:
        async with Client(provider.mcp_url) as c:  # no token
            r = await c.call_tool("navigate", {})
            assert r.is_error
            assert "deployment token required" in r.content[0].text
            r = await c.call_tool("status", {})
            assert not r.is_error
            assert r.structured_content["state"] == "IDLE"
        async with auth.mcp_client(provider.mcp_url) as c:  # Authorization: Bearer from the environment
            r = await c.call_tool("navigate", {})
            assert not r.is_error
            assert r.structured_content["accepted"] is True

    asyncio.run(asyncio.wait_for(talk(), 60))
    assert len(provider.goals) == 1  # type: ignore[attr-defined]
