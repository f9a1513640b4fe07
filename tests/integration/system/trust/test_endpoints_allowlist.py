"""Declared gRPC/MCP endpoints must name an allowed host: loopback by default, more when configured."""

from __future__ import annotations

import grpc
import pytest

from atlas.server import AtlasServer
from robonix_api.proto_gen import atlas_pb2

from .conftest import TOKEN, declare_grpc, md, raw_stub, register

NAV = "robonix/service/navigation/navigate"


@pytest.mark.parametrize("endpoint", ["evil.example.com:443", "grpc://evil.example.com:443", "10.0.0.7:50051",
                                      "dns:///evil.example.com:443", "[2001:db8::1]:80", "no-port-here:x"])
def test_foreign_grpc_endpoint_refused_naming_the_field(token_atlas: AtlasServer, endpoint: str) -> None:
    ch, stub = raw_stub(token_atlas.address)
    with ch:
        register(stub, "nav2", "robonix/service/navigation")
        with pytest.raises(grpc.RpcError) as err:
            declare_grpc(stub, "nav2", NAV, endpoint)
        assert err.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert err.value.details().startswith("endpoint: ")
        assert not stub.Query(atlas_pb2.QueryRequest(id="nav2"), timeout=5).providers[0].capabilities


def test_mcp_endpoint_checked_too_and_loopback_forms_pass(token_atlas: AtlasServer) -> None:
    ch, stub = raw_stub(token_atlas.address)
    with ch:
        register(stub, "nav2", "robonix/service/navigation")
        req = atlas_pb2.DeclareCapabilityRequest(provider_id="nav2", contract_id=NAV,
                                                 transport=atlas_pb2.TRANSPORT_MCP,
                                                 endpoint="http://evil.example.com:443/mcp/")
        req.params.mcp.input_schema_json = "{}"
        with pytest.raises(grpc.RpcError) as err:
            stub.DeclareCapability(req, timeout=5, metadata=md())
        assert err.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert "evil.example.com" in err.value.details()
        req.endpoint = "http://127.0.0.1:41237/mcp/"
        assert stub.DeclareCapability(req, timeout=5, metadata=md()).endpoint == req.endpoint
        for ep in ("127.0.0.1:5000", "localhost:5001", "[::1]:5002", "127.0.1.1:5003"):
            assert declare_grpc(stub, "nav2", f"{NAV}/x{ep[-1]}", ep) == ep


def test_allowed_hosts_extend_the_list() -> None:
    with AtlasServer("127.0.0.1:0", token=TOKEN, heartbeat_timeout_ms=0,
                     allowed_hosts="robot2.local, 192.168.1.20") as server:
        ch, stub = raw_stub(server.address)
        with ch:
            register(stub, "nav2", "robonix/service/navigation")
            assert declare_grpc(stub, "nav2", NAV, "robot2.local:7000") == "robot2.local:7000"
            assert declare_grpc(stub, "nav2", NAV + "/status", "192.168.1.20:7001") == "192.168.1.20:7001"
            with pytest.raises(grpc.RpcError) as err:
                declare_grpc(stub, "nav2", NAV + "/cancel", "evil.example.com:443")
            assert "robot2.local" in err.value.details()  # the message lists what is allowed
