"""Integration: real atlas server (in-process) + real providers (in-process threads and subprocesses)."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import grpc
import pytest
from support.procs import wait_until
from support.wire import decode, f_str, f_varint, one

from robonix_api import Deferred, Err, Ok, Service
from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import lifecycle_pb2, navigation_pb2, robonix_contracts_pb2_grpc
from robonix_api.types import LifecycleState

pytestmark = pytest.mark.integration

NAV = "robonix/service/navigation/navigate"
DRIVER = "robonix/lifecycle/driver"
DRIVER_PATH = "/robonix.contracts.RobonixLifecycleDriver/Driver"
REPO = Path(__file__).resolve().parents[3]


# ---------------------------------------------------------------- hand-rolled protobuf wire helpers

def driver_request_bytes(command: int, config_json: str = "") -> bytes:
    """Driver_Request built from field numbers: command=1 (varint), config_json=2 (string)."""
    return (f_varint(1, command) if command else b"") + (f_str(2, config_json) if config_json else b"")


def generic_driver(endpoint: str, command: int, config_json: str = "") -> tuple[bool, str, str]:
    with grpc.insecure_channel(endpoint) as ch:
        call = ch.unary_unary(DRIVER_PATH)  # no (de)serializers: raw bytes both ways
        reply = call(driver_request_bytes(command, config_json), timeout=30)
    f = decode(reply)
    return bool(one(f, 1, 0)), bytes(one(f, 2, b"")).decode(), bytes(one(f, 3, b"")).decode()


# ---------------------------------------------------------------- fixtures

@pytest.fixture
def client(atlas_server) -> AtlasClient:  # type: ignore[no-untyped-def]
    c = AtlasClient(atlas_server.address)
    yield c
    c.close()


@pytest.fixture
def providers(atlas_server, short_heartbeat):  # type: ignore[no-untyped-def]
    made: list[Service] = []

    def make(id: str = "sdk_p1") -> Service:
        svc = Service(id, "robonix/test", atlas=atlas_server.address)
        made.append(svc)
        return svc

    yield make
    for svc in made:
        svc.stop()


def provider_record(client: AtlasClient, pid: str):  # type: ignore[no-untyped-def]
    found = client.query(id=pid)
    return found[0] if found else None


def driver_endpoint(client: AtlasClient, pid: str) -> str:
    with client.connect_capability(consumer_id="test", provider_id=pid, contract_id=DRIVER,
                                   transport="grpc") as ch:
        return ch.endpoint


# ---------------------------------------------------------------- tests

def test_driver_over_real_grpc_stub_and_raw_bytes(providers, client: AtlasClient) -> None:  # type: ignore[no-untyped-def]
    svc = providers()
    seen: list[dict] = []
    svc.on_init(lambda cfg: seen.append(cfg) or Ok())
    svc.on_activate(lambda: Ok())
    svc.run_in_thread()

    rec = provider_record(client, "sdk_p1")
    assert rec is not None
    assert rec.state == LifecycleState.REGISTERED
    endpoint = driver_endpoint(client, "sdk_p1")
    assert endpoint == svc.grpc_endpoint

    # Generic unary call, request and reply handled as raw bytes (not our stubs).
    assert generic_driver(endpoint, 0, '{"speed": 0.5}') == (True, "inactive", "")
    assert seen == [{"speed": 0.5}]
    wait_until(lambda: provider_record(client, "sdk_p1").state == LifecycleState.INACTIVE, what="INACTIVE")
    ok, state, error = generic_driver(endpoint, 9)  # unknown command: ERROR, as robonix's SDK does
    assert (ok, state) == (False, "error")
    assert "command" in error
    assert provider_record(client, "sdk_p1").state == LifecycleState.ERROR
    assert generic_driver(endpoint, 0, "{}") == (True, "inactive", "")

    stub = robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(grpc.insecure_channel(endpoint))
    r = stub.Driver(lifecycle_pb2.Driver_Request(command=lifecycle_pb2.Driver_Request.CMD_ACTIVATE), timeout=30)
    assert (r.ok, r.state, r.error) == (True, "active", "")
    assert provider_record(client, "sdk_p1").state == LifecycleState.ACTIVE


def test_invalid_config_and_deferred(providers, client: AtlasClient) -> None:  # type: ignore[no-untyped-def]
    svc = providers()
    answers = iter([Deferred("waiting for robonix/primitive/lidar/lidar"), Err("lidar driver crashed")])
    svc.on_init(lambda cfg: next(answers))
    svc.run_in_thread()
    endpoint = driver_endpoint(client, "sdk_p1")

    with pytest.raises(grpc.RpcError) as bad:  # the RPC fails as in robonix's SDK, with the field named
        generic_driver(endpoint, 0, '{"speed": ,}')
    assert bad.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert bad.value.details().startswith("config_json: invalid JSON at line 1 column 11")
    assert provider_record(client, "sdk_p1").state == LifecycleState.REGISTERED

    assert generic_driver(endpoint, 0, "{}") == (False, "deferred", "waiting for robonix/primitive/lidar/lidar")
    rec = provider_record(client, "sdk_p1")
    assert rec.state == LifecycleState.REGISTERED
    assert rec.state_detail == "waiting for robonix/primitive/lidar/lidar"

    assert generic_driver(endpoint, 0, "{}") == (False, "error", "lidar driver crashed")
    rec = provider_record(client, "sdk_p1")
    assert rec.state == LifecycleState.ERROR
    assert rec.state_detail == "lidar driver crashed"


def test_grpc_contract_and_mcp_tool_through_atlas(providers, client: AtlasClient) -> None:  # type: ignore[no-untyped-def]
    from mcp import Client

    svc = providers()

    @svc.grpc(NAV)
    @svc.mcp(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        """Send the robot to a goal pose in the map frame."""
        return navigation_pb2.Navigate_Response(accepted=True, run_id="run-1",
                                                detail=f"to x={req.goal.pose.position.x}")

    svc.run_in_thread()
    (grpc_cap,) = client.find_capability(contract_id=NAV, transport="grpc")
    assert grpc_cap.params.service_name == "RobonixServiceNavigationNavigate"
    with client.connect_capability(consumer_id="test", provider_id="sdk_p1", contract_id=NAV,
                                   transport="grpc") as ch:
        stub = robonix_contracts_pb2_grpc.RobonixServiceNavigationNavigateStub(grpc.insecure_channel(ch.endpoint))
        req = navigation_pb2.Navigate_Request()
        req.goal.pose.position.x = 2.0
        assert stub.Navigate(req, timeout=30).detail == "to x=2.0"

    (mcp_cap,) = client.find_capability(contract_id=NAV, transport="mcp")
    assert '"goal"' in mcp_cap.params.input_schema_json
    with client.connect_capability(consumer_id="test", provider_id="sdk_p1", contract_id=NAV,
                                   transport="mcp") as ch:
        url = ch.endpoint
    assert url.startswith("http://127.0.0.1:")
    assert url.endswith("/mcp/")

    async def talk():  # type: ignore[no-untyped-def]
        async with Client(url) as mcp_client:
            tools = await mcp_client.list_tools()
            result = await mcp_client.call_tool("navigate", {"goal": {"pose": {"position": {"x": 3.5}}}})
            return tools, result

    tools, result = asyncio.run(asyncio.wait_for(talk(), 60))
    assert [t.name for t in tools.tools] == ["navigate"]
    assert tools.tools[0].description == "Send the robot to a goal pose in the map frame."
    assert result.structured_content == {"accepted": True, "run_id": "run-1", "detail": "to x=3.5"}
    assert "run-1" in result.content[0].text


def test_reregisters_after_atlas_restart(providers, client: AtlasClient, atlas_server) -> None:  # type: ignore[no-untyped-def]
    from atlas.server import AtlasServer

    svc = providers()

    @svc.grpc(NAV)
    def navigate(req):  # type: ignore[no-untyped-def]
        return navigation_pb2.Navigate_Response(accepted=True)

    svc.run_in_thread()
    assert generic_driver(svc.grpc_endpoint, 0) == (True, "inactive", "")
    assert generic_driver(svc.grpc_endpoint, 1) == (True, "active", "")
    address = atlas_server.address
    atlas_server.stop(0)
    fresh = AtlasServer(listen=address, heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    wait_until(lambda: _try_start(fresh), what="atlas restart on the same port")
    try:
        rec = wait_until(lambda: provider_record(client, "sdk_p1"), timeout_s=60, what="re-registration")
        wait_until(lambda: provider_record(client, "sdk_p1").state == LifecycleState.ACTIVE, what="ACTIVE again")
        rec = provider_record(client, "sdk_p1")
        assert {(c.contract_id, c.transport.label) for c in rec.capabilities} == {
            (DRIVER, "grpc"), ("robonix/test/driver", "grpc"), (NAV, "grpc")}
        assert driver_endpoint(client, "sdk_p1") == svc.grpc_endpoint
    finally:
        svc.stop()
        fresh.stop(0)


def _try_start(server) -> bool:  # type: ignore[no-untyped-def]
    try:
        server.start()
        return True
    except OSError:
        return False


PROVIDER_SCRIPT = textwrap.dedent("""
    import sys
    from pathlib import Path
    from robonix_api import Ok, Service

    out = Path(sys.argv[1])
    svc = Service("sdk_sub", "robonix/test")

    @svc.on_init
    def init(cfg):
        child = svc.spawn(["sleep", "600"])
        (out / "child.pid").write_text(str(child.pid))
        return Ok()

    @svc.on_shutdown
    def shutdown():
        (out / "shutdown.ran").write_text("yes")
        return Ok()

    svc.run()
    (out / "run.returned").write_text("yes")
""")


def _start_subprocess_provider(tmp_path: Path, atlas_address: str) -> subprocess.Popen:  # type: ignore[type-arg]
    (tmp_path / "package_manifest.yaml").write_text("manifestVersion: 1\n")
    (tmp_path / "CAPABILITY.md").write_text("# sdk_sub\nA test provider.\n")
    (tmp_path / "src").mkdir()
    script = tmp_path / "src" / "provider_main.py"  # pkg_root is found by walking up from here
    script.write_text(PROVIDER_SCRIPT)
    env = dict(os.environ, ROBONIX_ATLAS=atlas_address, ROBONIX_HEARTBEAT_PERIOD_S="0.5")
    env.pop("RBNX_INSTANCE_NAME", None)
    env.pop("RBNX_DEPLOY_MANAGED", None)
    return subprocess.Popen([sys.executable, str(script), str(tmp_path)], env=env, cwd=str(REPO))


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.parametrize("how", ["sigterm", "cmd_shutdown"])
def test_subprocess_provider_teardown(tmp_path: Path, atlas_server, client: AtlasClient, how: str) -> None:  # type: ignore[no-untyped-def]
    proc = _start_subprocess_provider(tmp_path, atlas_server.address)
    child_pid = 0
    try:
        wait_until(lambda: client.find_capability(contract_id=DRIVER, provider_id="sdk_sub"), timeout_s=90,
                   what="subprocess provider's Driver declared")
        rec = provider_record(client, "sdk_sub")
        assert rec.capability_md == "# sdk_sub\nA test provider.\n"
        assert rec.capability_md_path == str(tmp_path / "CAPABILITY.md")
        endpoint = driver_endpoint(client, "sdk_sub")
        assert generic_driver(endpoint, 0) == (True, "inactive", "")
        child_pid = int((tmp_path / "child.pid").read_text())
        assert _pid_alive(child_pid)
        if how == "sigterm":
            proc.send_signal(signal.SIGTERM)
        else:
            assert generic_driver(endpoint, 3) == (True, "terminated", "")
        assert proc.wait(timeout=90) == 0
        assert (tmp_path / "shutdown.ran").exists()
        assert (tmp_path / "run.returned").exists()
        assert provider_record(client, "sdk_sub").state == LifecycleState.TERMINATED
        wait_until(lambda: not _pid_alive(child_pid), what="spawned child gone")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
        if child_pid and _pid_alive(child_pid):
            os.kill(child_pid, signal.SIGKILL)
