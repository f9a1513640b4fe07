"""robonix-api 0.1.0rc1 behaviour on this SDK: the calls a robonix package makes, run here.

Names and signatures are compared with the real wheel in tests/compat/test_robonix_api_conformance.py;
these tests check what the calls *do* (argument orders told apart, robonix-api's error behaviour on
``ATLAS``, ROS message names on DDS, provider helpers), each against a real atlas or DDS where it matters.
"""

from __future__ import annotations

import asyncio
import importlib
import json
import sys
import threading
from pathlib import Path

import grpc
import pytest
from support.fakes import FakeAtlas
from support.procs import wait_until

from robonix_api import (
    ATLAS,
    Capability,
    CapabilityProvider,
    Channel,
    ContractDescriptor,
    Deferred,
    Err,
    GrpcParams,
    Kind,
    LifecycleState,
    McpParams,
    Ok,
    Primitive,
    Result,
    Ros2Params,
    Service,
    Transport,
    mcp_contract,
)
from robonix_api.atlas_client import AtlasClient, RobonixAtlas, split_transport_endpoint
from robonix_api.proto_gen import lifecycle_pb2, map_pb2
from robonix_api.types import FieldSpec

LIDAR = "robonix/primitive/lidar/lidar"
GET_MODE = "robonix/service/map/get_mode"
GET_POSE = "robonix/service/map/get_pose"


# ------------------------------------------------------------------ results and data types

def test_result_types_have_robonix_fields() -> None:
    err = Err("lidar unplugged")
    assert err.message == "lidar unplugged"
    assert err.msg == "lidar unplugged"
    assert Err(message="a") == Err("a") == Err(msg="a")
    assert not err
    assert Deferred("later").reason == "later"
    assert Ok()
    assert isinstance(Ok(), Result.__args__)
    with pytest.raises(AttributeError):
        err.message = "x"  # type: ignore[misc]  (frozen, as robonix-api's)


def test_dataclasses_accept_robonix_positional_order() -> None:
    ours = Capability("p", Kind.SERVICE, GET_POSE, Transport.MCP, McpParams("{}"), "tool")
    theirs = Capability("p", Kind.SERVICE, GET_POSE, Transport.MCP, "tool", McpParams("{}"))
    assert theirs == ours
    assert Capability("p", Kind.SERVICE, GET_POSE, Transport.MCP, "tool").params is None

    closed: list[str] = []
    ch = Channel("lidar", LIDAR, Transport.ROS2, "/scan", "ch-1", Ros2Params("best_effort"), closed.append)
    assert (ch.provider_id, ch.contract_id, ch.transport, ch.endpoint, ch.channel_id) == (
        "lidar", LIDAR, Transport.ROS2, "/scan", "ch-1")
    assert ch.params == Ros2Params("best_effort")
    assert ch.qos_profile == "best_effort"
    with ch:
        pass
    ch.close()
    assert closed == ["ch-1"]  # robonix-api's _closer, called once
    assert Channel("ch-2", "/odom", None, "odom", "c", Transport.ROS2).endpoint == "/odom"  # our order

    desc = ContractDescriptor(LIDAR, "1", Kind.PRIMITIVE, "topic_out", "sensor_msgs/msg/LaserScan", "", "x.toml",
                              "a lidar", (FieldSpec("header", "std_msgs/Header"),))
    assert desc.description == "a lidar"
    assert desc.msg_fields[0].name == "header"
    assert CapabilityProvider("p", Kind.PRIMITIVE, "ns").state == LifecycleState.UNSPECIFIED
    assert GrpcParams().proto_file == "robonix_contracts.proto"
    assert McpParams().input_schema_json == "{}"


def test_lifecycle_state_equals_its_name() -> None:
    assert LifecycleState.ACTIVE == "active"
    assert LifecycleState.ACTIVE != "inactive"
    assert LifecycleState.ACTIVE == 3
    assert {LifecycleState.ACTIVE: 1}[3] == 1


def test_transport_and_endpoint_in_either_order() -> None:
    assert split_transport_endpoint(Transport.ROS2, "/scan") == (Transport.ROS2, "/scan")  # robonix-api
    assert split_transport_endpoint("/scan", "ros2") == (Transport.ROS2, "/scan")  # ours
    assert split_transport_endpoint("127.0.0.1:5", 1) == (Transport.GRPC, "127.0.0.1:5")
    assert split_transport_endpoint("ros", "/odom") == (Transport.ROS2, "/odom")  # robonix-api's alias
    with pytest.raises(ValueError, match="cannot tell which"):
        split_transport_endpoint("/a", "/b")


# ------------------------------------------------------------------ ATLAS against a real atlas

@pytest.mark.integration
def test_atlas_robonix_calls_on_a_real_atlas(atlas_server) -> None:  # type: ignore[no-untyped-def]
    atlas = RobonixAtlas(atlas_server.address)
    try:
        assert atlas.register_primitive("c_lidar", "robonix/primitive/lidar") == "c_lidar"
        assert atlas.register_service("c_map", "robonix/service/map") == "c_map"
        assert atlas.register_skill("c_skill", "robonix/skill/demo") == "c_skill"
        # robonix-api's order, then ours: both land the same way
        declared = atlas.declare_capability("c_lidar", LIDAR, Transport.ROS2, "/c_scan", Ros2Params("best_effort"))
        assert declared == "/c_scan"
        atlas.declare_capability("c_map", GET_MODE, "127.0.0.1:9", "grpc")
        atlas.declare_capability(provider_id="c_map", contract_id=GET_POSE, transport="mcp",
                                 endpoint="http://127.0.0.1:9/mcp/", description="pose")
        assert [p.id for p in atlas.query_primitives()] == ["c_lidar"]
        assert [p.id for p in atlas.query_services()] == ["c_map"]
        assert [p.id for p in atlas.query_skills()] == ["c_skill"]
        every = atlas.find_capability()  # no contract: every live capability
        assert {(c.provider_id, c.contract_id) for c in every} >= {("c_lidar", LIDAR), ("c_map", GET_MODE),
                                                                  ("c_map", GET_POSE)}
        grpc_cap = atlas.find_unique_capability(contract_id=GET_MODE)
        assert grpc_cap.params == GrpcParams("robonix_contracts.proto")  # robonix-api's default params
        ch = atlas.connect_capability(consumer_id="c_map", provider_id="c_lidar", contract_id=LIDAR,
                                      transport=Transport.ROS2)
        assert atlas.disconnect_capability(ch.channel_id) is True
        assert atlas.disconnect_capability(ch.channel_id) is False
        assert [c.id for c in atlas.list_contracts(namespace_prefix="robonix/service/map/get_")] == [
            GET_MODE, GET_POSE]
        hb = atlas.start_heartbeat("c_lidar", period_s=0.05)
        assert isinstance(hb, threading.Thread)
        assert hb.daemon
        assert hb.is_alive()
        wait_until(lambda: hb.beats >= 2, 30, "two heartbeats")  # type: ignore[attr-defined]
        hb.stop()  # type: ignore[attr-defined]
        assert atlas.unregister("c_skill") is True
        assert atlas.unregister("c_skill") is False
    finally:
        atlas.close()


def test_atlas_swallows_errors_like_robonix_but_atlas_client_raises() -> None:
    dead = RobonixAtlas("127.0.0.1:1")
    dead.timeout = 2.0
    try:
        assert dead.heartbeat("x") is None
        assert dead.unregister("x") is False
        assert dead.disconnect_capability("c") is False
        assert dead.query() == []
        assert dead.query_primitives() == []
        assert dead.find_capability(contract_id=LIDAR) == []
        assert dead.list_contracts() == []
        assert dead.query_contract(LIDAR) is None
        assert dead.inspect() == {}
        with pytest.raises(grpc.RpcError):  # registering, declaring and connecting raise in robonix-api too
            dead.register_service("x", "robonix/service/x")
        with pytest.raises(ValueError, match="no live provider"):
            dead.find_unique_capability(contract_id=LIDAR)
    finally:
        dead.close()
    strict = AtlasClient("127.0.0.1:1")
    strict.timeout = 2.0
    try:
        with pytest.raises(grpc.RpcError):
            strict.heartbeat("x")
        with pytest.raises(grpc.RpcError):
            strict.query()
    finally:
        strict.close()
    assert isinstance(ATLAS, RobonixAtlas)
    assert importlib.import_module("robonix_api.atlas").ATLAS is ATLAS


# ------------------------------------------------------------------ ROS names on DDS

def test_ros_message_names_resolve_to_dds_classes() -> None:
    from robonix_api.dds import LaserScan, Odometry
    from robonix_api.ros import RosBackend, qos_and_depth, resolve_msg_type

    assert resolve_msg_type("LaserScan") is LaserScan is resolve_msg_type("sensor_msgs/msg/LaserScan")
    assert resolve_msg_type("nav_msgs/Odometry") is Odometry
    assert resolve_msg_type(Odometry) is Odometry
    assert resolve_msg_type("sensor_msgs/msg/PointCloud2").__name__ == "PointCloud2"  # 3D lidars (issue 38)
    with pytest.raises(ImportError, match="JointState"):
        resolve_msg_type("JointState")
    with pytest.raises(ValueError, match="unrecognized"):
        resolve_msg_type("a/b/c/d")
    assert qos_and_depth(5) == ("reliable", 5)
    assert qos_and_depth("latched") == ("latched", None)
    with pytest.raises(ValueError, match="unknown QoS preset"):
        qos_and_depth("fast")
    assert RosBackend.get() is RosBackend.get()


# ------------------------------------------------------------------ provider helpers

def test_provider_robonix_surface(tmp_path: Path, fake_atlas: FakeAtlas, clean_env: None,
                                  short_heartbeat: float) -> None:
    with pytest.raises(ValueError, match="namespace must be non-empty"):
        Service("x", "/", atlas=fake_atlas)
    svc = Service("c1", "/robonix/service/map/", atlas=fake_atlas, pkg_root=tmp_path)
    assert svc.namespace == "robonix/service/map"
    assert svc.state == LifecycleState.REGISTERED

    @svc.on_init
    def init(cfg: dict) -> Ok:
        return Ok()

    with pytest.raises(RuntimeError, match="already registered"):
        svc.on_init(init)

    @svc.provides_grpc(GET_MODE)
    def get_mode(req: map_pb2.GetMode_Request) -> map_pb2.GetMode_Response:
        """The mode, over gRPC."""
        return map_pb2.GetMode_Response(ok=True, mode="x")

    @svc.provides_mcp(GET_POSE, description="Pose, as a tool.")
    def get_pose(req: map_pb2.GetPose_Request) -> map_pb2.GetPose_Response:
        return map_pb2.GetPose_Response(ok=True, x=1.5)

    with pytest.raises(RuntimeError, match="call create_publisher") as exc:
        svc.emit(LIDAR, None)
    assert isinstance(exc.value, KeyError)  # what this SDK raised before

    svc.bootstrap()
    try:
        svc.bootstrap()  # idempotent
        assert svc.mcp_endpoint == svc.mcp_url
        assert svc.mcp_endpoint.endswith("/mcp/")
        declared = fake_atlas.declared
        assert declared[("c1", GET_MODE, Transport.GRPC)]["description"] == "The mode, over gRPC."
        assert declared[("c1", GET_POSE, Transport.MCP)]["description"] == "Pose, as a tool."
        assert declared[("c1", "robonix/service/map/driver", Transport.GRPC)]["params"].method == "Driver"
        svc.create_publisher(contract_id=LIDAR, topic="/c1_scan", msg_type="LaserScan", qos=3,
                             description="scans")
        decl = declared[("c1", LIDAR, Transport.ROS2)]
        assert decl["params"] == Ros2Params("reliable")
        assert decl["description"] == "scans"
        assert svc.declare_ros2_service("robonix/service/map/save_map", "/save_map") == "/save_map"
        assert declared[("c1", "robonix/service/map/save_map", Transport.ROS2)]["params"] == Ros2Params("")
        assert svc.declare_grpc("robonix/service/map/list_maps", "127.0.0.1:7", "Svc", "M") == "127.0.0.1:7"
        assert declared[("c1", "robonix/service/map/list_maps", Transport.GRPC)]["params"] == GrpcParams(
            "robonix_contracts.proto", "Svc", "M")
        assert svc.resolve_host_ip("127.0.0.1") == "127.0.0.1"
        svc.stop()  # after bootstrap() (no run loop), stop() tears down itself
        assert svc.wait(0)
        assert fake_atlas.states[-1][1] == LifecycleState.TERMINATED
    finally:
        svc.stop()


def test_spawn_adds_env_and_logs_like_robonix(tmp_path: Path, fake_atlas: FakeAtlas) -> None:
    from robonix_api.spawn import SpawnRegistry

    svc = Primitive("c2", "robonix/primitive/x", atlas=fake_atlas, pkg_root=tmp_path)
    proc = svc.spawn(["bash", "-c", 'echo "$C2_VALUE ${PATH:+has-path}"'], env={"C2_VALUE": 42}, log="child.log")
    assert proc.wait(30) == 0
    assert (tmp_path / "rbnx-build" / "data" / "child.log").read_text() == "42 has-path\n"
    reg = SpawnRegistry()
    child = reg.spawn(["bash", "-c", "echo $R; exec sleep 60"], env={"R": "r"}, log_path=tmp_path / "r.log")
    wait_until(lambda: (tmp_path / "r.log").read_text() == "r\n", 30, "the child's output")
    reg.shutdown_all(term_grace_s=5.0)
    assert child.poll() is not None


@pytest.mark.integration
def test_connect_capability_and_subscription_from_channel(atlas_server, clean_env: None,  # type: ignore[no-untyped-def]
                                                          short_heartbeat: float, tmp_path: Path) -> None:
    from robonix_api.ros import resolve_msg_type

    lidar = Primitive("c_lidar2", "robonix/primitive/lidar", atlas=atlas_server.address, pkg_root=tmp_path)
    watcher = Service("c_watch", "robonix/service/map", atlas=atlas_server.address, pkg_root=tmp_path)
    lidar.run_in_thread()
    watcher.run_in_thread()
    client = AtlasClient(atlas_server.address)
    try:
        lidar.create_publisher(contract_id=LIDAR, topic="/c_scan2", msg_type="sensor_msgs/msg/LaserScan")
        cap = RobonixAtlas(atlas_server.address).find_unique_capability(contract_id=LIDAR, transport="ros2")
        ch = watcher.connect_capability(cap, LIDAR, "ros2")
        got: list[object] = []
        watcher.create_subscription_from_channel(ch, msg_type="LaserScan", callback=got.append)
        scan = resolve_msg_type("LaserScan")()
        scan.ranges = [1.25] * 4

        def delivered() -> bool:
            lidar.emit(LIDAR, scan)
            return bool(got)

        wait_until(delivered, 60, "a LaserScan through the channel's topic")
        assert list(got[0].ranges) == [1.25] * 4  # type: ignore[attr-defined]
        assert watcher.wait_for_topic("/c_scan2", "LaserScan", timeout_s=0.3) is False  # no message: False
        quiet = threading.Event()

        def keep_publishing() -> None:
            while not quiet.wait(0.05):
                lidar.emit(LIDAR, scan)

        threading.Thread(target=keep_publishing, daemon=True).start()
        try:
            assert watcher.wait_for_topic("/c_scan2", "sensor_msgs/msg/LaserScan", timeout_s=60) is True
        finally:
            quiet.set()
        assert any(c["channel_id"] == ch.channel_id for c in client.inspect()["channels"])
        watcher.stop()
        assert not any(c["channel_id"] == ch.channel_id for c in client.inspect()["channels"])  # closed on teardown
    finally:
        client.close()
        watcher.stop()
        lidar.stop()


def test_mcp_contract_on_the_official_mcp_server_and_use_mcp_app(fake_atlas: FakeAtlas, clean_env: None,
                                                                 tmp_path: Path) -> None:
    from mcp import Client
    from mcp.server.mcpserver import MCPServer

    app = MCPServer("c3")

    @mcp_contract(app, contract_id=GET_POSE)
    def get_pose(req: map_pb2.GetPose_Request) -> map_pb2.GetPose_Response:
        """Pose as a tool."""
        return map_pb2.GetPose_Response(ok=True, x=2.5, frame_id="map")

    assert get_pose._robonix_contract_id == GET_POSE
    assert get_pose._robonix_input_cls is map_pb2.GetPose_Request
    with pytest.raises(TypeError, match="exactly one parameter"):
        mcp_contract(app, contract_id=GET_MODE)(lambda a, b: None)

    svc = Service("c3", "robonix/service/map", atlas=fake_atlas, pkg_root=tmp_path)
    svc.use_mcp_app(app)
    svc.run_in_thread()
    try:
        decl = fake_atlas.declared[("c3", GET_POSE, Transport.MCP)]
        assert decl["endpoint"] == svc.mcp_endpoint
        assert decl["description"] == "Pose as a tool."

        async def talk() -> dict:  # type: ignore[type-arg]
            async with Client(svc.mcp_endpoint) as client:
                res = await client.call_tool("get_pose", {})
                assert not res.is_error, res.content
                return json.loads(res.content[0].text)

        assert asyncio.run(asyncio.wait_for(talk(), 60)) == {"ok": True, "x": 2.5, "y": 0.0, "theta": 0.0,
                                                              "frame_id": "map", "detail": ""}
        with pytest.raises(RuntimeError, match="use_mcp_app"):
            svc.use_mcp_app(MCPServer("other"))
    finally:
        svc.stop()


def test_lifecycle_module_builds_a_driver_servicer() -> None:
    from robonix_api import lifecycle
    from robonix_api.proto_gen import robonix_contracts_pb2_grpc

    commands = (lifecycle.CMD_INIT, lifecycle.CMD_ACTIVATE, lifecycle.CMD_DEACTIVATE, lifecycle.CMD_SHUTDOWN)
    assert commands == (0, 1, 2, 3)
    assert lifecycle.driver_pascal_for_namespace("robonix/primitive/lidar") == "RobonixPrimitiveLidarDriver"
    assert lifecycle.build_lifecycle_servicer("robonix/nowhere", robonix_contracts_pb2_grpc,
                                              lifecycle_pb2.Driver_Response) is None
    pushed: list[tuple[object, str]] = []
    inits: list[dict] = []  # type: ignore[type-arg]

    def on_init(cfg: dict) -> Ok | Deferred:  # type: ignore[type-arg]
        inits.append(cfg)
        return Deferred("no lidar yet") if len(inits) == 1 else Ok()

    built = lifecycle.build_lifecycle_servicer(
        "robonix/lifecycle", robonix_contracts_pb2_grpc, lifecycle_pb2.Driver_Response, on_init=on_init,
        on_state_change=lambda state, detail: pushed.append((state, detail)))
    assert built is not None
    servicer, add_fn, base, method = built
    assert (base, method) == ("RobonixLifecycleDriver", "Driver")
    assert callable(add_fn)
    req = lifecycle_pb2.Driver_Request
    r = servicer.Driver(req(command=0, config_json='{"a": 1}'), None)
    assert (r.ok, r.state, r.error) == (False, "deferred", "no lidar yet")
    r = servicer.Driver(req(command=0, config_json='{"a": 1}'), None)
    assert (r.ok, r.state) == (True, "inactive")
    assert inits == [{"a": 1}, {"a": 1}]
    assert pushed == [(None, "no lidar yet"), ("inactive", "")]
    assert lifecycle.parse_cfg(req(config_json="[1]")) == {}
    with pytest.raises(ValueError, match="bad config_json"):
        lifecycle.parse_cfg(req(config_json="{"))


def test_generated_protos_importable_by_top_level_name(tmp_path: Path) -> None:
    import map_pb2 as top  # type: ignore[import-not-found]  (robonix codegen's layout)

    from robonix_api.codegen import ensure_proto_gen, find_pkg_root

    assert top is map_pb2
    (tmp_path / "package_manifest.yaml").write_text("manifestVersion: 1\n")
    gen = tmp_path / "rbnx-build" / "codegen" / "proto_gen"
    gen.mkdir(parents=True)
    (gen / "atlas_pb2.py").write_text("")
    (tmp_path / "src").mkdir()
    try:
        assert find_pkg_root(tmp_path / "src") == tmp_path
        assert ensure_proto_gen(tmp_path / "src") == gen.parent
        assert str(gen) in sys.path
    finally:
        sys.path.remove(str(gen))


ECHO_TYPES = '''
from dataclasses import asdict, dataclass


@dataclass
class Echo_Request:
    text: str = ""
    times: int = 1

    @classmethod
    def json_schema(cls):
        return {"type": "object", "properties": {"text": {"type": "string"}, "times": {"type": "integer"}}}

    @classmethod
    def from_dict(cls, d):
        return cls(**d)


@dataclass
class Echo_Response:
    text: str = ""

    def to_dict(self):
        return asdict(self)


def echo(req: Echo_Request) -> Echo_Response:
    """Repeat the text."""
    return Echo_Response(text=req.text * req.times)
'''


def test_mcp_tool_of_a_package_contract_with_codegen_types(tmp_path: Path, fake_atlas: FakeAtlas,
                                                           clean_env: None) -> None:
    """A robonix package's own MCP contract (not in our catalogue) with its codegen input/output classes,
    found in the package's rbnx-build/codegen as robonix-api finds them."""
    from mcp import Client

    (tmp_path / "package_manifest.yaml").write_text("manifestVersion: 1\n")
    codegen = tmp_path / "rbnx-build" / "codegen"
    (codegen / "proto_gen").mkdir(parents=True)
    (codegen / "proto_gen" / "atlas_pb2.py").write_text("")
    (codegen / "robonix_mcp_types").mkdir()
    (codegen / "robonix_mcp_types" / "c4_echo_types.py").write_text(ECHO_TYPES)
    svc = Service("c4", "robonix/service/demo", atlas=fake_atlas, pkg_root=tmp_path)
    try:
        echo_types = importlib.import_module("c4_echo_types")  # on sys.path now, as with robonix-api
        svc.provides_mcp("robonix/service/demo/echo")(echo_types.echo)
        with pytest.raises(KeyError, match="not in the catalogue"):
            svc.provides_mcp("robonix/service/demo/other")(lambda req: None)
        svc.run_in_thread()
        decl = fake_atlas.declared[("c4", "robonix/service/demo/echo", Transport.MCP)]
        assert json.loads(decl["params"].input_schema_json)["properties"]["times"] == {"type": "integer"}

        async def talk() -> dict:  # type: ignore[type-arg]
            async with Client(svc.mcp_endpoint) as client:
                res = await client.call_tool("echo", {"text": "ab", "times": 3})
                assert not res.is_error, res.content
                return dict(res.structured_content or {})

        assert asyncio.run(asyncio.wait_for(talk(), 60)) == {"text": "ababab"}
    finally:
        svc.stop()
        for sub in ("proto_gen", "robonix_mcp_types"):
            if str(codegen / sub) in sys.path:
                sys.path.remove(str(codegen / sub))
        sys.modules.pop("c4_echo_types", None)


def test_bundled_proto_names_win_over_a_package_copy(tmp_path: Path) -> None:
    """A package's own ``robonix_contracts_pb2`` next to ours would be a duplicate proto file name, which
    protobuf refuses; the bundled module answers the name, the package's other modules still load."""
    gen = tmp_path / "proto_gen"
    gen.mkdir()
    (gen / "robonix_contracts_pb2.py").write_text("raise ImportError('the package copy was imported')\n")
    (gen / "c5_speech_pb2.py").write_text("import robonix_contracts_pb2\nOURS = robonix_contracts_pb2\n")
    sys.path.insert(0, str(gen))
    try:
        sys.modules.pop("robonix_contracts_pb2", None)
        speech = importlib.import_module("c5_speech_pb2")
        from robonix_api.proto_gen import robonix_contracts_pb2

        assert speech.OURS is robonix_contracts_pb2
    finally:
        sys.path.remove(str(gen))
        sys.modules.pop("c5_speech_pb2", None)
