"""robonix_api.types (enum parsing, pb round trips) and atlas.catalogue (FieldSpecs from the stubs)."""

from __future__ import annotations

import pytest

from atlas.catalogue import Catalogue, build_descriptor
from robonix_api import types as rt
from robonix_api.contracts import load_catalogue
from robonix_api.proto_gen import atlas_pb2


def test_enum_values_match_proto() -> None:
    for enum, prefix in ((rt.Kind, "KIND_"), (rt.Transport, "TRANSPORT_"), (rt.LifecycleState, "STATE_")):
        for member in enum:
            assert getattr(atlas_pb2, prefix + member.name) == member.value


@pytest.mark.parametrize(
    ("enum", "value", "expected"),
    [
        (rt.Transport, "ros2", rt.Transport.ROS2),
        (rt.Transport, "TRANSPORT_GRPC", rt.Transport.GRPC),
        (rt.Transport, 3, rt.Transport.MCP),
        (rt.Transport, None, rt.Transport.UNSPECIFIED),
        (rt.Kind, "Primitive", rt.Kind.PRIMITIVE),
        (rt.Kind, "KIND_SKILL", rt.Kind.SKILL),
        (rt.LifecycleState, "active", rt.LifecycleState.ACTIVE),
        (rt.LifecycleState, "STATE_TERMINATED", rt.LifecycleState.TERMINATED),
        (rt.LifecycleState, rt.LifecycleState.ERROR, rt.LifecycleState.ERROR),
    ],
)
def test_enum_parse(enum, value, expected) -> None:
    assert enum.parse(value) is expected


def test_enum_parse_errors() -> None:
    with pytest.raises(ValueError, match="ros3"):
        rt.Transport.parse("ros3")
    with pytest.raises(ValueError, match="Kind: unknown value 7"):
        rt.Kind.parse(7)
    with pytest.raises(TypeError):
        rt.Kind.parse(1.5)


@pytest.mark.parametrize(
    "params", [rt.GrpcParams("f.proto", "Svc", "M"), rt.Ros2Params("reliable"), rt.McpParams("{}"), None]
)
def test_params_roundtrip(params) -> None:
    assert rt.params_from_pb(rt.params_to_pb(params)) == params


def test_provider_roundtrip() -> None:
    cap = rt.Capability("p", rt.Kind.SERVICE, "c/x", rt.Transport.MCP, rt.McpParams("{}"), "d", True)
    prov = rt.CapabilityProvider(
        "p", rt.Kind.SERVICE, "ns", "md", 5, rt.LifecycleState.ACTIVE, "ok", [cap], "# md", "rid"
    )
    wire = prov.to_pb().SerializeToString()
    assert rt.CapabilityProvider.from_pb(atlas_pb2.CapabilityProvider.FromString(wire)) == prov


def test_descriptor_roundtrip_and_fields() -> None:
    cat = Catalogue.load()
    for desc in cat.list():
        assert rt.ContractDescriptor.from_pb(desc.to_pb()) == desc
    odom = cat.get("robonix/primitive/chassis/odom")
    assert odom.io_msg_type == "nav_msgs/msg/Odometry"
    assert odom.io_srv_type == ""
    assert odom.msg_fields[0] == rt.FieldSpec("header", "std_msgs/Header", False)
    scan = {f.name: f for f in cat.get("robonix/primitive/lidar/lidar").msg_fields}
    assert scan["ranges"] == rt.FieldSpec("ranges", "float32", True, True, 0)
    assert scan["angle_min"].type_name == "float32"
    grid = {f.name: f for f in cat.get("robonix/service/map/occupancy_grid").msg_fields}
    assert grid["data"] == rt.FieldSpec("data", "int8", True, True, 0)
    assert grid["info"].type_name == "nav_msgs/MapMetaData"
    nav = cat.get("robonix/service/navigation/navigate")
    assert nav.io_srv_type == "navigation/srv/Navigate"
    assert nav.msg_fields == ()
    assert nav.srv_request_fields == (rt.FieldSpec("goal", "geometry_msgs/PoseStamped", False),)
    assert [f.name for f in nav.srv_response_fields] == ["accepted", "run_id", "detail"]
    driver = cat.get("robonix/lifecycle/driver")
    assert driver.cross_namespace
    assert driver.kind == rt.Kind.SERVICE
    assert driver.srv_request_fields[0] == rt.FieldSpec("command", "uint8", True)


def test_every_contract_resolves_to_generated_types(caplog: pytest.LogCaptureFixture) -> None:
    specs = load_catalogue()
    with caplog.at_level("WARNING", logger="atlas.catalogue"):
        descs = [build_descriptor(s) for s in specs.values()]
    assert not caplog.records, [r.getMessage() for r in caplog.records]
    for d in descs:
        assert d.msg_fields or d.srv_response_fields, d.id
