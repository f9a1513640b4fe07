"""The atlas with a deployment token: every change needs it, reading does not; without one it is
robonix's open atlas. Real gRPC against an in-process AtlasServer."""

from __future__ import annotations

import grpc
import pytest

from atlas.server import AtlasServer
from robonix_api.atlas_client import AtlasClient
from robonix_api.auth import TOKEN_ENV
from robonix_api.proto_gen import atlas_pb2

from .conftest import TOKEN, declare_grpc, md, raw_stub, register

NAV = "robonix/service/navigation/navigate"


def _code(fn: object) -> grpc.StatusCode:
    with pytest.raises(grpc.RpcError) as err:
        fn()  # type: ignore[operator]
    return err.value.code()


def test_mutating_rpcs_need_the_token_and_name_it(token_atlas: AtlasServer) -> None:
    ch, stub = raw_stub(token_atlas.address)
    with ch:
        with pytest.raises(grpc.RpcError) as err:
            register(stub, "nav2", "robonix/service/navigation", token=None)
        assert err.value.code() == grpc.StatusCode.UNAUTHENTICATED
        assert "robonix-token" in err.value.details()
        assert "RegisterService" in err.value.details()
        with pytest.raises(grpc.RpcError) as err:
            register(stub, "nav2", "robonix/service/navigation", token="wrong")
        assert err.value.code() == grpc.StatusCode.PERMISSION_DENIED

        assert register(stub, "nav2", "robonix/service/navigation") == "nav2"
        assert declare_grpc(stub, "nav2", NAV, "127.0.0.1:5555") == "127.0.0.1:5555"
        calls = {
            "Heartbeat": lambda m: stub.Heartbeat(atlas_pb2.HeartbeatRequest(id="nav2"), timeout=5, metadata=m),
            "SetLifecycleState": lambda m: stub.SetLifecycleState(atlas_pb2.SetLifecycleStateRequest(
                id="nav2", state=atlas_pb2.STATE_TERMINATED), timeout=5, metadata=m),
            "ConnectCapability": lambda m: stub.ConnectCapability(atlas_pb2.ConnectCapabilityRequest(
                consumer_id="x", provider_id="nav2", contract_id=NAV, transport=atlas_pb2.TRANSPORT_GRPC),
                timeout=5, metadata=m),
            "DisconnectCapability": lambda m: stub.DisconnectCapability(
                atlas_pb2.DisconnectCapabilityRequest(channel_id="ch-1"), timeout=5, metadata=m),
            "Unregister": lambda m: stub.Unregister(atlas_pb2.UnregisterRequest(id="nav2"), timeout=5, metadata=m),
        }
        for name, call in calls.items():
            assert _code(lambda call=call: call(None)) == grpc.StatusCode.UNAUTHENTICATED, name
            assert _code(lambda call=call: call(md("nope"))) == grpc.StatusCode.PERMISSION_DENIED, name

        # Reading stays open: Query, QueryContract, ListContracts, InspectAtlas without any token.
        (prov,) = stub.Query(atlas_pb2.QueryRequest(id="nav2"), timeout=5).providers
        assert prov.state != atlas_pb2.STATE_TERMINATED
        assert prov.capabilities[0].contract_id == NAV
        assert stub.QueryContract(atlas_pb2.QueryContractRequest(contract_id=NAV), timeout=5).found
        assert stub.ListContracts(atlas_pb2.ListContractsRequest(), timeout=5).contracts
        assert "nav2" in stub.InspectAtlas(atlas_pb2.InspectAtlasRequest(), timeout=5).json

        # With the token every one of them runs.
        for call in calls.values():
            call(md())


def test_sdk_client_sends_the_token_from_the_environment(token_atlas: AtlasServer,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    with AtlasClient(token_atlas.address) as client:
        with pytest.raises(grpc.RpcError) as err:
            client.register_service("hal", "robonix/primitive/chassis")
        assert err.value.code() == grpc.StatusCode.UNAUTHENTICATED
        monkeypatch.setenv(TOKEN_ENV, TOKEN)  # read per call: the same client now carries it
        assert client.register_service("hal", "robonix/primitive/chassis") == "hal"
        assert client.registration_ids["hal"]  # our atlas answers with the registration id
        client.heartbeat("hal")
        assert client.set_state("hal", "active") is not None


def test_atlas_without_token_is_open_as_robonix(open_atlas: AtlasServer) -> None:
    ch, stub = raw_stub(open_atlas.address)
    with ch:
        assert register(stub, "nav2", "robonix/service/navigation", token=None) == "nav2"
        # robonix's takeover: a second Register of a live id replaces it
        assert register(stub, "nav2", "robonix/service/navigation", token=None) == "nav2"
        stub.SetLifecycleState(atlas_pb2.SetLifecycleStateRequest(id="nav2", state=atlas_pb2.STATE_ACTIVE),
                               timeout=5)
        assert stub.Unregister(atlas_pb2.UnregisterRequest(id="nav2"), timeout=5).was_present
