"""Integration tests: the real gRPC atlas (in-process, port 0) through raw stubs and AtlasClient."""

from __future__ import annotations

import json
import socket
import threading

import grpc
import pytest
from support.wait import wait_until

from atlas.server import AtlasServer
from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import atlas_pb2 as pb
from robonix_api.types import Kind, LifecycleState, McpParams, Ros2Params, Transport

ODOM = "robonix/primitive/chassis/odom"
SCAN = "robonix/primitive/lidar/lidar"
DRIVER = "robonix/lifecycle/driver"


def rpc_error(fn, *args, **kwargs) -> grpc.RpcError:
    with pytest.raises(grpc.RpcError) as info:
        fn(*args, **kwargs)
    return info.value


# --------------------------------------------------------------------------- raw stubs


def test_register_takeover_and_errors(stub, uid: str) -> None:
    pid = f"chassis-{uid}"
    assert stub.RegisterPrimitive(pb.RegisterRequest(id=pid, namespace="robonix/primitive/chassis")).id == pid
    first = stub.Query(pb.QueryRequest(id=pid)).providers[0].registration_id
    assert stub.RegisterPrimitive(pb.RegisterRequest(id=pid, namespace="robonix/primitive/chassis")).id == pid
    second = stub.Query(pb.QueryRequest(id=pid)).providers[0].registration_id
    assert first
    assert second
    assert first != second

    e = rpc_error(stub.RegisterService, pb.RegisterRequest(id=pid, namespace="robonix/service/x"))
    assert e.code() == grpc.StatusCode.ALREADY_EXISTS
    assert e.details().startswith("id:")
    e = rpc_error(stub.RegisterSkill, pb.RegisterRequest(id=f"s-{uid}", namespace=""))
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert e.details() == "namespace: must not be empty"
    eph = stub.RegisterSkill(pb.RegisterRequest(namespace="robonix/skill")).id
    assert eph.startswith("com.robonix.ephemeral.")
    assert stub.Unregister(pb.UnregisterRequest(id=eph)).was_present
    assert not stub.Unregister(pb.UnregisterRequest(id=eph)).was_present


def test_heartbeat_not_found(stub) -> None:
    e = rpc_error(stub.Heartbeat, pb.HeartbeatRequest(id="nobody-here"))
    assert e.code() == grpc.StatusCode.NOT_FOUND
    assert "nobody-here" in e.details()
    e = rpc_error(stub.Heartbeat, pb.HeartbeatRequest(id=""))
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT


def test_declare_rules_over_grpc(stub, uid: str) -> None:
    a, b = f"a-{uid}", f"b-{uid}"
    for pid in (a, b):
        stub.RegisterPrimitive(pb.RegisterRequest(id=pid, namespace="robonix/primitive/chassis"))
    ros2 = pb.TransportParams(ros2=pb.Ros2Params(qos_profile="reliable"))
    grpc_params = pb.TransportParams(grpc=pb.GrpcParams(proto_file="robonix_contracts.proto"))

    def declare(pid, cid, transport, endpoint, params):
        req = pb.DeclareCapabilityRequest(
            provider_id=pid, contract_id=cid, transport=transport, endpoint=endpoint
        )
        if params is not None:
            req.params.CopyFrom(params)
        return stub.DeclareCapability(req).endpoint

    e = rpc_error(declare, a, ODOM, pb.TRANSPORT_ROS2, "", None)
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert e.details().startswith("params:")
    e = rpc_error(declare, a, ODOM, pb.TRANSPORT_ROS2, "", grpc_params)
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert e.details().startswith("params:")
    e = rpc_error(declare, a, ODOM, pb.TRANSPORT_UNSPECIFIED, "/x", ros2)
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert e.details().startswith("transport:")
    e = rpc_error(declare, a, DRIVER, pb.TRANSPORT_GRPC, "", grpc_params)
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert e.details().startswith("endpoint:")

    minted = declare(a, ODOM, pb.TRANSPORT_ROS2, "", ros2)
    assert minted.startswith("/rbnx/robonix/primitive/chassis/odom/t")
    e = rpc_error(declare, a, ODOM, pb.TRANSPORT_ROS2, "/other", ros2)
    assert e.code() == grpc.StatusCode.ALREADY_EXISTS

    topic = f"/scan_{uid}"
    assert declare(a, SCAN, pb.TRANSPORT_ROS2, topic, ros2) == topic
    rewritten = declare(b, SCAN, pb.TRANSPORT_ROS2, topic, ros2)
    assert rewritten.startswith(topic + "_t")
    assert "__" not in rewritten

    port_ep = f"127.0.0.1:{40000 + int(uid[:4], 16) % 20000}"
    declare(a, DRIVER, pb.TRANSPORT_GRPC, port_ep, grpc_params)
    e = rpc_error(declare, b, DRIVER, pb.TRANSPORT_GRPC, port_ep, grpc_params)
    assert e.code() == grpc.StatusCode.ALREADY_EXISTS
    assert e.details().startswith("endpoint:")
    # the provider's <namespace>/driver may stand next to the shared robonix/lifecycle/driver ...
    assert declare(a, "robonix/primitive/chassis/driver", pb.TRANSPORT_GRPC, port_ep, grpc_params) == port_ep
    # ... but a provider has one driver of its own (robonix rule)
    e = rpc_error(declare, a, "robonix/primitive/lidar/driver", pb.TRANSPORT_GRPC, port_ep, grpc_params)
    assert e.code() == grpc.StatusCode.FAILED_PRECONDITION


def test_connect_and_contracts_over_grpc(stub, uid: str) -> None:
    pid = f"c-{uid}"
    stub.RegisterPrimitive(pb.RegisterRequest(id=pid, namespace="robonix/primitive/chassis"))
    e = rpc_error(
        stub.ConnectCapability,
        pb.ConnectCapabilityRequest(
            consumer_id="nav", provider_id=pid, contract_id="robonix/no/such", transport=pb.TRANSPORT_ROS2
        ),
    )
    assert e.code() == grpc.StatusCode.NOT_FOUND
    assert e.details().startswith("contract_id:")

    resp = stub.QueryContract(pb.QueryContractRequest(contract_id="robonix/no/such"))
    assert resp.found is False
    assert resp.HasField("contract")
    assert resp.contract.id == ""
    e = rpc_error(stub.QueryContract, pb.QueryContractRequest(contract_id=""))
    assert e.code() == grpc.StatusCode.INVALID_ARGUMENT

    ids = [
        c.id
        for c in stub.ListContracts(pb.ListContractsRequest(namespace_prefix="robonix/service/")).contracts
    ]
    assert ids == sorted(ids)
    assert ids
    assert all(i.startswith("robonix/service/") for i in ids)
    assert len(stub.ListContracts(pb.ListContractsRequest()).contracts) >= 31
    snap = json.loads(stub.InspectAtlas(pb.InspectAtlasRequest()).json)
    assert {"providers", "capabilities", "channels", "contracts"} <= snap.keys()


# --------------------------------------------------------------------------- AtlasClient


def test_client_end_to_end(client: AtlasClient, uid: str) -> None:
    chassis, mapping = f"chassis-{uid}", f"mapping-{uid}"
    assert (
        client.register("primitive", chassis, "robonix/primitive/chassis", capability_md="# chassis")
        == chassis
    )
    client.register_service(mapping, "robonix/service/map")
    odom_topic = client.declare_capability(chassis, ODOM, f"/odom_{uid}", "ros2", Ros2Params("reliable"))
    assert odom_topic == f"/odom_{uid}"
    client.declare_capability(chassis, DRIVER, "127.0.0.1:1", Transport.GRPC)  # default (empty) params
    mcp_ep = "http://127.0.0.1:2/mcp/"
    client.declare_capability(
        mapping, ODOM, mcp_ep, 3, McpParams('{"type": "object"}'), description="odom tool"
    )

    assert client.set_state(chassis, "active") == LifecycleState.INACTIVE
    [p] = client.query(id=chassis)
    assert p.kind == Kind.PRIMITIVE
    assert p.state == LifecycleState.ACTIVE
    assert p.capability_md == "# chassis"
    assert {c.contract_id for c in p.capabilities} == {ODOM, DRIVER}

    caps = client.find_capability(contract_id=ODOM, provider_id=chassis)
    assert [(c.provider_id, c.transport) for c in caps] == [(chassis, Transport.ROS2)]
    assert len(client.find_capability(contract_id=ODOM, namespace_prefix="robonix/service/map")) >= 1
    cap = client.find_unique_capability(contract_id=ODOM, transport="ros2", provider_id=chassis)
    assert cap.params == Ros2Params("reliable")
    with pytest.raises(ValueError, match="no live provider offers contract 'robonix/none'"):
        client.find_unique_capability(contract_id="robonix/none")
    with pytest.raises(ValueError, match=rf"{chassis}.*{mapping}|{mapping}.*{chassis}"):
        client.find_unique_capability(contract_id=ODOM, namespace_prefix="robonix/")

    with client.connect_capability(
        consumer_id="nav", provider_id=chassis, contract_id=ODOM, transport="ros2"
    ) as ch:
        assert ch.endpoint == odom_topic
        assert ch.qos_profile == "reliable"
        assert ch.provider_id == chassis
        assert any(c["channel_id"] == ch.channel_id for c in client.inspect()["channels"])
    assert not any(c["channel_id"] == ch.channel_id for c in client.inspect()["channels"])
    assert ch.close() is False  # idempotent

    with pytest.raises(grpc.RpcError) as info:
        client.connect_capability(
            consumer_id="nav", provider_id=chassis, contract_id="robonix/x", transport="ros2"
        )
    assert info.value.code() == grpc.StatusCode.NOT_FOUND

    # TERMINATED providers are invisible to find_capability but still in raw query
    client.set_state(chassis, LifecycleState.TERMINATED, "shutdown")
    assert client.find_capability(contract_id=ODOM, provider_id=chassis) == []
    assert client.query(id=chassis)[0].state == LifecycleState.TERMINATED
    assert client.unregister(chassis)
    assert client.unregister(mapping)


def test_client_contracts(client: AtlasClient) -> None:
    d = client.query_contract(ODOM)
    assert d is not None
    assert d.kind == Kind.PRIMITIVE
    assert d.mode == "topic_out"
    assert [f.name for f in d.msg_fields] == ["header", "child_frame_id", "pose", "twist"]
    assert client.query_contract("robonix/nope") is None
    maps = client.list_contracts("robonix/service/map/")
    assert [c.id for c in maps] == sorted(c.id for c in maps)
    assert len(maps) >= 10
    assert client.inspect()["contracts"] == len(client.list_contracts())


def test_heartbeat_handle_calls_on_not_found(client: AtlasClient, uid: str) -> None:
    pid = f"hb-{uid}"
    client.register_skill(pid, "robonix/skill")
    recovered = threading.Event()

    def on_not_found() -> None:  # what the SDK does: register again
        client.register_skill(pid, "robonix/skill")
        recovered.set()

    handle = client.start_heartbeat(pid, period_s=0.05, on_not_found=on_not_found)
    try:
        wait_until(lambda: handle.beats >= 2, 15.0, "two heartbeats")
        client.unregister(pid)  # looks like an atlas restart to the provider
        assert recovered.wait(15.0)
        wait_until(lambda: client.query(id=pid), 15.0, "re-registration")
    finally:
        handle.stop()
    assert not handle.running
    client.unregister(pid)


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_heartbeat_survives_unavailable_atlas() -> None:
    dead = AtlasClient(f"127.0.0.1:{_free_port()}")  # nothing listens there
    dead.timeout = 0.5
    attempts: list[str] = []
    real_heartbeat = dead.heartbeat_or_raise

    def counted(pid: str) -> None:  # the real call, counted: proves the loop kept trying
        attempts.append(pid)
        real_heartbeat(pid)

    dead.heartbeat_or_raise = counted  # type: ignore[method-assign]
    handle = dead.start_heartbeat("x", period_s=0.02, on_not_found=lambda: None)
    try:
        wait_until(lambda: len(attempts) >= 3, 30.0, lambda: f"three heartbeat attempts, got {len(attempts)}")
        assert handle.running
        assert handle.beats == 0
    finally:
        handle.stop()
        dead.close()
    assert not handle.running


def test_client_address_and_enum_parsing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROBONIX_ATLAS", "127.0.0.1:59999")
    assert AtlasClient().address == "127.0.0.1:59999"
    assert AtlasClient("10.0.0.1:1").address == "10.0.0.1:1"
    monkeypatch.delenv("ROBONIX_ATLAS")
    assert AtlasClient().address == "127.0.0.1:50051"
    with pytest.raises(ValueError, match="Kind: unknown name 'robot'"):
        AtlasClient("127.0.0.1:1").register("robot", "x", "ns")


# --------------------------------------------------------------------------- eviction (own atlas)


def test_eviction_terminates_drops_channels_and_allows_reregister() -> None:
    server = AtlasServer(
        "127.0.0.1:0", heartbeat_timeout_ms=300, eviction_interval_ms=100, gc_after_terminated_ms=600000
    )
    addr = server.start()
    client = AtlasClient(addr)
    registry = server.registry
    try:
        # Eviction is paused (timeout 0) while setting up, so a slow machine cannot evict too early.
        registry.heartbeat_timeout_ms = 0
        client.register_primitive("lapsing", "robonix/primitive/chassis")
        client.declare_capability("lapsing", ODOM, "/odom", "ros2", Ros2Params("reliable"))
        ch = client.connect_capability(
            consumer_id="nav", provider_id="lapsing", contract_id=ODOM, transport="ros2"
        )
        rid = client.query(id="lapsing")[0].registration_id
        registry.heartbeat_timeout_ms = 300

        p = wait_until(
            lambda: next(
                (p for p in client.query(id="lapsing") if p.state == LifecycleState.TERMINATED), None
            ),
            15.0, "TERMINATED by eviction",
        )
        assert p.state_detail == "heartbeat lapsed > 300ms"
        assert client.inspect()["channels"] == []
        assert ch.close() is False
        # as robonix's atlas: the channel opens, the record says TERMINATED, find_capability hides it
        late = client.connect_capability(consumer_id="nav", provider_id="lapsing", contract_id=ODOM,
                                         transport="ros2")
        assert late.endpoint
        assert late.close() is True
        assert not client.find_capability(contract_id=ODOM, provider_id="lapsing")

        registry.heartbeat_timeout_ms = 0  # again: the re-registered provider must not lapse mid-assert
        client.register_primitive("lapsing", "robonix/primitive/chassis")
        [p] = client.query(id="lapsing")
        assert p.state == LifecycleState.REGISTERED
        assert p.registration_id != rid
        assert p.capabilities == []
        assert client.declare_capability("lapsing", ODOM, "/odom", "ros2") == "/odom"
    finally:
        client.close()
        server.stop(0)


def test_port_in_use_is_refused(atlas_server: AtlasServer) -> None:
    with pytest.raises(OSError, match="listen"):
        AtlasServer(atlas_server.address).start()
    with pytest.raises(ValueError, match="listen"):
        AtlasServer("no-port-here").start()
