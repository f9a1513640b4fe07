"""Provider tests against a recording fake atlas: real gRPC/MCP servers, no atlas process."""

from __future__ import annotations

import asyncio
from pathlib import Path

import grpc
import pytest
from support.fakes import FakeAtlas
from support.procs import wait_until

from robonix_api import Deferred, Ok, Primitive, Service, Skill, StatusError
from robonix_api.driver import CMD_ACTIVATE, CMD_INIT
from robonix_api.proto_gen import lifecycle_pb2, navigation_pb2, robonix_contracts_pb2_grpc
from robonix_api.types import GrpcParams, Kind, LifecycleState, McpParams, Transport

NAV = "robonix/service/navigation/navigate"
DRIVER = "robonix/lifecycle/driver"


@pytest.fixture
def provider(fake_atlas: FakeAtlas, clean_env: None, short_heartbeat: float):  # type: ignore[no-untyped-def]
    made: list[Service] = []

    def make(cls: type = Service, **kw):  # type: ignore[no-untyped-def]
        svc = cls(kw.pop("id", "p1"), kw.pop("namespace", "robonix/test"), atlas=fake_atlas, **kw)
        made.append(svc)
        return svc

    yield make
    for svc in made:
        svc.stop()


def driver_stub(svc: Service) -> robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub:
    return robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(grpc.insecure_channel(svc.grpc_endpoint))


def test_register_declare_and_drive(provider, fake_atlas: FakeAtlas) -> None:  # type: ignore[no-untyped-def]
    svc = provider(Primitive)

    @svc.grpc(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        return navigation_pb2.Navigate_Response(accepted=True, run_id=req.goal.header.frame_id)

    svc.run_in_thread()
    reg = fake_atlas.registrations[0]
    assert reg["kind"] == Kind.PRIMITIVE
    assert reg["id"] == "p1"
    assert reg["namespace"] == "robonix/test"
    drv = fake_atlas.declared[("p1", DRIVER, Transport.GRPC)]
    assert drv["endpoint"] == svc.grpc_endpoint
    assert svc.grpc_endpoint.startswith("127.0.0.1:")
    assert drv["params"] == GrpcParams("robonix_contracts.proto", "RobonixLifecycleDriver", "Driver")
    nav = fake_atlas.declared[("p1", NAV, Transport.GRPC)]
    assert nav["params"] == GrpcParams("robonix_contracts.proto", "RobonixServiceNavigationNavigate", "Navigate")

    stub = driver_stub(svc)
    r = stub.Driver(lifecycle_pb2.Driver_Request(command=CMD_INIT, config_json="{}"), timeout=30)
    assert (r.ok, r.state) == (True, "inactive")
    r = stub.Driver(lifecycle_pb2.Driver_Request(command=CMD_ACTIVATE), timeout=30)
    assert (r.ok, r.state) == (True, "active")
    # REGISTERED is said at once (robonix's executor reads INACTIVE as "initialised"), then the transitions
    assert [s for _, s, _ in fake_atlas.states] == [LifecycleState.REGISTERED, LifecycleState.INACTIVE,
                                                     LifecycleState.ACTIVE]

    # the same Driver under robonix-api's per-namespace name, at both gRPC paths robonix callers use
    ns_drv = fake_atlas.declared[("p1", "robonix/test/driver", Transport.GRPC)]
    assert ns_drv["params"] == GrpcParams("robonix_contracts.proto", "RobonixTestDriver", "Driver")
    with grpc.insecure_channel(svc.grpc_endpoint) as ch:
        for path in ("/robonix.contracts.RobonixTestDriver/Driver", "/robonix.contracts.TestDriver/Driver"):
            call = ch.unary_unary(path, request_serializer=lifecycle_pb2.Driver_Request.SerializeToString,
                                  response_deserializer=lifecycle_pb2.Driver_Response.FromString)
            r = call(lifecycle_pb2.Driver_Request(command=CMD_ACTIVATE), timeout=30)
            assert (r.ok, r.state) == (True, "active")

    nav_stub = robonix_contracts_pb2_grpc.RobonixServiceNavigationNavigateStub(
        grpc.insecure_channel(svc.grpc_endpoint))
    req = navigation_pb2.Navigate_Request()
    req.goal.header.frame_id = "map"
    assert nav_stub.Navigate(req, timeout=30).run_id == "map"

    r = stub.Driver(lifecycle_pb2.Driver_Request(command=3), timeout=30)
    assert (r.ok, r.state) == (True, "terminated")
    assert svc.wait(30)
    assert fake_atlas.states[-1][1] == LifecycleState.TERMINATED


def test_handler_errors_become_statuses(provider) -> None:  # type: ignore[no-untyped-def]
    svc = provider()

    @svc.grpc(NAV)
    def navigate(req, ctx):  # type: ignore[no-untyped-def]
        if not req.goal.header.frame_id:
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, "goal.header.frame_id is required")
        raise RuntimeError("planner exploded")

    svc.run_in_thread()
    stub = robonix_contracts_pb2_grpc.RobonixServiceNavigationNavigateStub(
        grpc.insecure_channel(svc.grpc_endpoint))
    with pytest.raises(grpc.RpcError) as ei:
        stub.Navigate(navigation_pb2.Navigate_Request(), timeout=30)
    assert ei.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "frame_id" in ei.value.details()
    req = navigation_pb2.Navigate_Request()
    req.goal.header.frame_id = "map"
    with pytest.raises(grpc.RpcError) as ei:
        stub.Navigate(req, timeout=30)
    assert ei.value.code() == grpc.StatusCode.INTERNAL
    assert "planner exploded" in ei.value.details()


def test_reregisters_when_atlas_forgets(provider, fake_atlas: FakeAtlas) -> None:  # type: ignore[no-untyped-def]
    svc = provider(Skill)
    svc.on_init(lambda cfg: Ok())
    svc.run_in_thread()
    svc.declare_ros2_topic("robonix/primitive/lidar/lidar", "/scan")
    driver_stub(svc).Driver(lifecycle_pb2.Driver_Request(command=CMD_INIT), timeout=30)
    fake_atlas.forget()
    wait_until(lambda: len(fake_atlas.registrations) >= 2, what="re-registration")
    wait_until(lambda: ("p1", LifecycleState.INACTIVE, "") in fake_atlas.states[1:], what="state re-push")
    assert {k[1] for k in fake_atlas.declared} == {DRIVER, "robonix/test/driver", "robonix/primitive/lidar/lidar"}
    assert fake_atlas.registrations[1]["kind"] == Kind.SKILL


def test_deferred_reason_pushed(provider, fake_atlas: FakeAtlas) -> None:  # type: ignore[no-untyped-def]
    svc = provider()
    svc.on_init(lambda cfg: Deferred("no provider of robonix/service/map/occupancy_grid"))
    svc.run_in_thread()
    r = driver_stub(svc).Driver(lifecycle_pb2.Driver_Request(command=CMD_INIT), timeout=30)
    assert (r.ok, r.state, r.error) == (False, "deferred", "no provider of robonix/service/map/occupancy_grid")
    assert fake_atlas.states == [("p1", LifecycleState.REGISTERED, ""), ("p1", LifecycleState.REGISTERED, r.error)]


def test_identity_from_env_and_package(tmp_path: Path, monkeypatch, fake_atlas: FakeAtlas,  # type: ignore[no-untyped-def]
                                       clean_env: None) -> None:
    (tmp_path / "package_manifest.yaml").write_text("manifestVersion: 1\n")
    (tmp_path / "CAPABILITY.md").write_text("# Test package\n")
    (tmp_path / "src").mkdir()
    monkeypatch.setenv("RBNX_INSTANCE_NAME", "from_env")
    svc = Service("in_code", "robonix/test", pkg_root=tmp_path, atlas=fake_atlas)
    assert svc.id == "from_env"
    assert svc.pkg_root == tmp_path
    assert svc.capability_md == "# Test package\n"
    assert svc.md_path == str(tmp_path / "CAPABILITY.md")
    from robonix_api.pkg import find_pkg_root

    assert find_pkg_root(tmp_path / "src" / "x.py") == tmp_path
    monkeypatch.setenv("RBNX_INSTANCE_NAME", "")
    monkeypatch.setenv("RBNX_DEPLOY_MANAGED", "1")
    with pytest.raises(ValueError, match="RBNX_INSTANCE_NAME"):
        Service("in_code", "robonix/test", atlas=fake_atlas)


def test_advertise_host(monkeypatch, clean_env: None) -> None:  # type: ignore[no-untyped-def]
    from robonix_api import netutil

    assert netutil.bind_host() == "127.0.0.1"
    assert netutil.advertise_host("127.0.0.1", "127.0.0.1:50051") == "127.0.0.1"
    assert netutil.advertise_host(netutil.WILDCARD_V4, "127.0.0.1:50051") == "127.0.0.1"  # route source to loopback
    monkeypatch.setenv("ROBONIX_ADVERTISE_HOST", "10.1.2.3")
    assert netutil.advertise_host(netutil.WILDCARD_V4, "127.0.0.1:50051") == "10.1.2.3"
    monkeypatch.setenv("ROBONIX_PROVIDER_BIND_HOST", "localhost")
    with pytest.raises(ValueError, match="ROBONIX_PROVIDER_BIND_HOST"):
        netutil.bind_host()


def test_mcp_schema_from_request_proto() -> None:
    from robonix_api.proto_gen import map_pb2
    from robonix_api.proto_schema import message_schema

    s = message_schema(navigation_pb2.Navigate_Request.DESCRIPTOR)
    goal = s["properties"]["goal"]
    assert goal["type"] == "object"
    assert goal["properties"]["pose"]["properties"]["position"]["properties"]["x"] == {"type": "number"}
    assert goal["properties"]["header"]["properties"]["frame_id"] == {"type": "string"}
    s = message_schema(map_pb2.LoadMap_Request.DESCRIPTOR)
    assert s["properties"]["has_initial_pose"] == {"type": "boolean"}


def test_mcp_tool_over_streamable_http(provider, fake_atlas: FakeAtlas) -> None:  # type: ignore[no-untyped-def]
    from mcp import Client

    svc = provider()

    @svc.mcp(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        """Drive the robot to a goal pose."""
        return navigation_pb2.Navigate_Response(accepted=req.goal.pose.position.x > 0, run_id="r1")

    svc.run_in_thread()
    decl = fake_atlas.declared[("p1", NAV, Transport.MCP)]
    assert decl["endpoint"] == svc.mcp_url
    assert svc.mcp_url.endswith("/mcp/")
    assert isinstance(decl["params"], McpParams)
    assert '"goal"' in decl["params"].input_schema_json

    async def talk() -> tuple:  # type: ignore[type-arg]
        async with Client(svc.mcp_url) as client:
            tools = await client.list_tools()
            ok = await client.call_tool("navigate", {"goal": {"pose": {"position": {"x": 1.0}}}})
            bad = await client.call_tool("navigate", {"goall": {}})
            return tools, ok, bad

    tools, ok, bad = asyncio.run(asyncio.wait_for(talk(), 60))
    (tool,) = tools.tools
    assert tool.name == "navigate"
    assert tool.description == "Drive the robot to a goal pose."
    assert tool.input_schema["properties"]["goal"]["type"] == "object"
    assert not ok.is_error
    assert ok.structured_content == {"accepted": True, "run_id": "r1", "detail": ""}
    assert bad.is_error
    assert "goall" in bad.content[0].text
