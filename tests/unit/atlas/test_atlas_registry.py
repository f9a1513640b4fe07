"""Unit tests of atlas.registry: spec §1.5 rules with a fake clock (no gRPC, no sleeping)."""

from __future__ import annotations

import json
import re

import pytest

from atlas.catalogue import Catalogue
from atlas.registry import (
    EPHEMERAL_PREFIX,
    Registry,
    RegistryError,
    is_valid_ros2_name,
    mint_ros2_endpoint,
    rewrite_ros2_endpoint,
)
from robonix_api.types import GrpcParams, Kind, LifecycleState, McpParams, Ros2Params, Transport

ODOM = "robonix/primitive/chassis/odom"
SCAN = "robonix/primitive/lidar/lidar"
DRIVER = "robonix/lifecycle/driver"
G, R, M = Transport.GRPC, Transport.ROS2, Transport.MCP


class FakeClock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t

    def advance_ms(self, ms: float) -> None:
        self.t += ms / 1000.0


@pytest.fixture(scope="module")
def catalogue() -> Catalogue:
    return Catalogue.load()


@pytest.fixture
def clock() -> FakeClock:
    return FakeClock()


@pytest.fixture
def reg(catalogue: Catalogue, clock: FakeClock) -> Registry:
    return Registry(catalogue, heartbeat_timeout_ms=1000, gc_after_terminated_ms=5000, clock=clock)


def err(code: str, field: str):
    """Context manager asserting a RegistryError with this code whose message starts with the field."""

    class _Ctx:
        def __enter__(self):
            self.cm = pytest.raises(RegistryError)
            self.info = self.cm.__enter__()
            return self.info

        def __exit__(self, *exc):
            handled = self.cm.__exit__(*exc)
            assert self.info.value.code == code, self.info.value
            assert self.info.value.message.startswith(f"{field}:"), self.info.value.message
            return handled

    return _Ctx()


def chassis(reg: Registry, pid: str = "chassis") -> str:
    return reg.register(Kind.PRIMITIVE, pid, "robonix/primitive/chassis")


# --------------------------------------------------------------------------- register / unregister


def test_register_and_ephemeral_id(reg: Registry) -> None:
    assert chassis(reg) == "chassis"
    eid = reg.register(Kind.SERVICE, "", "robonix/service/x")
    assert eid.startswith(EPHEMERAL_PREFIX)
    assert len(eid) > len(EPHEMERAL_PREFIX) + 30
    [p] = reg.query(id="chassis")
    assert p.kind == Kind.PRIMITIVE
    assert p.state == LifecycleState.REGISTERED
    assert p.registration_id


def test_register_errors(reg: Registry) -> None:
    with err("INVALID_ARGUMENT", "namespace"):
        reg.register(Kind.PRIMITIVE, "x", "")
    with err("INVALID_ARGUMENT", "kind"):
        reg.register(Kind.UNSPECIFIED, "x", "ns")
    chassis(reg)
    with err("ALREADY_EXISTS", "id") as info:
        reg.register(Kind.SERVICE, "chassis", "robonix/service/x")
    assert "primitive" in info.value.message


def test_takeover_resets_everything(reg: Registry, clock: FakeClock) -> None:
    chassis(reg)
    reg.declare("chassis", ODOM, R, "/odom", Ros2Params("reliable"))
    reg.set_state("chassis", LifecycleState.ACTIVE, "running")
    reg.connect("nav", "chassis", ODOM, R)
    first = reg.query(id="chassis")[0]
    clock.advance_ms(500)
    chassis(reg)
    [p] = reg.query(id="chassis")
    assert p.registration_id != first.registration_id
    assert p.capabilities == []
    assert p.state == LifecycleState.REGISTERED
    assert p.state_detail == ""
    assert reg.channel_count() == 0
    # the endpoint is free again for the new registration
    assert reg.declare("chassis", ODOM, R, "/odom", Ros2Params("reliable")) == "/odom"


def test_registration_id_stable_across_heartbeat_state_declare(reg: Registry) -> None:
    chassis(reg)
    rid = reg.query(id="chassis")[0].registration_id
    reg.heartbeat("chassis")
    reg.set_state("chassis", LifecycleState.INACTIVE)
    reg.declare("chassis", ODOM, R, "", Ros2Params())
    assert reg.query(id="chassis")[0].registration_id == rid


def test_unregister_idempotent_drops_channels(reg: Registry) -> None:
    chassis(reg)
    reg.declare("chassis", ODOM, R, "/odom", Ros2Params())
    reg.connect("nav", "chassis", ODOM, R)
    assert reg.unregister("chassis") is True
    assert reg.unregister("chassis") is False
    assert reg.channel_count() == 0
    assert reg.query() == []


# --------------------------------------------------------------------------- heartbeat / state


def test_heartbeat_errors(reg: Registry) -> None:
    with err("INVALID_ARGUMENT", "id"):
        reg.heartbeat("")
    with err("NOT_FOUND", "id"):
        reg.heartbeat("ghost")


def test_set_state_rules(reg: Registry) -> None:
    chassis(reg)
    with err("INVALID_ARGUMENT", "state"):
        reg.set_state("chassis", LifecycleState.UNSPECIFIED)
    with err("NOT_FOUND", "id"):
        reg.set_state("ghost", LifecycleState.ACTIVE)
    assert (
        reg.set_state("chassis", LifecycleState.ACTIVE, "skip") == LifecycleState.REGISTERED
    )  # odd edge: stored
    assert reg.set_state("chassis", LifecycleState.INACTIVE) == LifecycleState.ACTIVE
    assert reg.query(id="chassis")[0].state == LifecycleState.INACTIVE


def test_implicit_state_driver_only_vs_other(reg: Registry) -> None:
    chassis(reg)
    reg.declare("chassis", DRIVER, G, "127.0.0.1:1", GrpcParams("robonix_contracts.proto", "X", "Driver"))
    assert reg.query(id="chassis")[0].state == LifecycleState.REGISTERED
    reg.declare("chassis", ODOM, R, "", Ros2Params())
    assert reg.query(id="chassis")[0].state == LifecycleState.INACTIVE


# --------------------------------------------------------------------------- declare


def test_declare_argument_errors(reg: Registry) -> None:
    chassis(reg)
    with err("INVALID_ARGUMENT", "provider_id"):
        reg.declare("", ODOM, R, "", Ros2Params())
    with err("NOT_FOUND", "provider_id"):
        reg.declare("ghost", ODOM, R, "", Ros2Params())
    with err("INVALID_ARGUMENT", "contract_id"):
        reg.declare("chassis", "", R, "", Ros2Params())
    with err("INVALID_ARGUMENT", "transport"):
        reg.declare("chassis", ODOM, Transport.UNSPECIFIED, "/odom", Ros2Params())
    with err("INVALID_ARGUMENT", "transport"):
        reg.declare("chassis", ODOM, 9, "/odom", Ros2Params())
    with err("INVALID_ARGUMENT", "params"):
        reg.declare("chassis", ODOM, R, "/odom", None)
    with err("INVALID_ARGUMENT", "params"):
        reg.declare("chassis", ODOM, R, "/odom", GrpcParams())
    with err("INVALID_ARGUMENT", "endpoint"):
        reg.declare("chassis", ODOM, G, "", GrpcParams())
    with err("INVALID_ARGUMENT", "endpoint"):
        reg.declare("chassis", ODOM, M, "", McpParams())
    with err("INVALID_ARGUMENT", "params.mcp.input_schema_json"):
        reg.declare("chassis", ODOM, M, "http://h:1/mcp/", McpParams("[1, 2]"))
    with err("INVALID_ARGUMENT", "params.mcp.input_schema_json"):
        reg.declare("chassis", ODOM, M, "http://h:1/mcp/", McpParams("{nope"))
    assert reg.query(id="chassis")[0].capabilities == []
    assert reg.declare("chassis", ODOM, M, "http://h:1/mcp/", McpParams('{"type": "object"}'))


def test_declare_duplicate_and_second_driver(reg: Registry) -> None:
    chassis(reg)
    reg.declare("chassis", ODOM, R, "/odom", Ros2Params())
    with err("ALREADY_EXISTS", "contract_id"):
        reg.declare("chassis", ODOM, R, "/odom2", Ros2Params())
    reg.declare("chassis", ODOM, G, "127.0.0.1:5", GrpcParams())  # same contract, other transport: fine
    reg.declare("chassis", DRIVER, G, "127.0.0.1:5", GrpcParams())
    reg.declare("chassis", DRIVER, M, "http://127.0.0.1:6/mcp/", McpParams())  # same driver, other transport
    # the namespace driver may stand next to the shared one (robonix-api callers look it up) ...
    reg.declare("chassis", "robonix/primitive/chassis/driver", G, "127.0.0.1:5", GrpcParams())
    with err("FAILED_PRECONDITION", "contract_id"):  # ... but not a second driver of its own
        reg.declare("chassis", "robonix/primitive/lidar/driver", G, "127.0.0.1:5", GrpcParams())


def test_ros2_minting_is_valid(reg: Registry) -> None:
    chassis(reg)
    ep = reg.declare("chassis", ODOM, R, "", Ros2Params("reliable"))
    assert re.fullmatch(r"/rbnx/robonix/primitive/chassis/odom/t[0-9a-f]{8}", ep), ep
    assert is_valid_ros2_name(ep)
    assert reg.connect("c", "chassis", ODOM, R).endpoint == ep


def test_endpoint_collisions(reg: Registry) -> None:
    chassis(reg, "a")
    chassis(reg, "b")
    assert reg.declare("a", ODOM, R, "/odom", Ros2Params()) == "/odom"
    rewritten = reg.declare("b", ODOM, R, "/odom", Ros2Params())
    assert rewritten != "/odom"
    assert rewritten.startswith("/odom_t")
    assert is_valid_ros2_name(rewritten)
    reg.declare("a", DRIVER, G, "127.0.0.1:7000", GrpcParams())
    with err("ALREADY_EXISTS", "endpoint") as info:
        reg.declare("b", DRIVER, G, "127.0.0.1:7000", GrpcParams())
    assert "'a'" in info.value.message
    reg.declare("a", SCAN, M, "http://127.0.0.1:7001/mcp/", McpParams())
    with err("ALREADY_EXISTS", "endpoint"):
        reg.declare("b", SCAN, M, "http://127.0.0.1:7001/mcp/", McpParams())
    # one provider may reuse its own endpoint across contracts
    assert reg.declare("a", SCAN, G, "127.0.0.1:7000", GrpcParams()) == "127.0.0.1:7000"
    # same endpoint string on a different transport is no collision
    assert reg.declare("b", SCAN, R, "127.0.0.1:7000", Ros2Params()) == "127.0.0.1:7000"


def test_terminated_owner_does_not_collide(reg: Registry) -> None:
    chassis(reg, "a")
    chassis(reg, "b")
    reg.declare("a", DRIVER, G, "127.0.0.1:7000", GrpcParams())
    reg.set_state("a", LifecycleState.TERMINATED)
    assert reg.declare("b", DRIVER, G, "127.0.0.1:7000", GrpcParams()) == "127.0.0.1:7000"


def test_namespace_mismatch_diagnostic(reg: Registry) -> None:
    chassis(reg)
    reg.declare("chassis", ODOM, R, "", Ros2Params())
    reg.declare("chassis", SCAN, R, "", Ros2Params())
    reg.declare("chassis", DRIVER, G, "h:1", GrpcParams())  # cross_namespace contract
    flags = {c.contract_id: c.namespace_mismatch for c in reg.query(id="chassis")[0].capabilities}
    assert flags == {ODOM: False, SCAN: True, DRIVER: False}


# --------------------------------------------------------------------------- query


def _populate(reg: Registry) -> None:
    chassis(reg, "chassis")
    reg.register(Kind.SERVICE, "mapping", "robonix/service/map")
    reg.register(Kind.SKILL, "skill", "robonix/skill/x")
    reg.declare("chassis", ODOM, R, "/odom", Ros2Params("reliable"))
    reg.declare("chassis", SCAN, R, "/scan", Ros2Params("best_effort"))
    reg.declare("mapping", ODOM, G, "127.0.0.1:9", GrpcParams())
    reg.declare("mapping", "robonix/service/map/occupancy_grid", R, "/map", Ros2Params("transient_local"))


def test_query_filters(reg: Registry) -> None:
    _populate(reg)
    assert [p.id for p in reg.query()] == ["chassis", "mapping", "skill"]
    assert [p.id for p in reg.query(kind=Kind.SERVICE)] == ["mapping"]
    assert [p.id for p in reg.query(id="skill")] == ["skill"]
    assert reg.query(id="nobody") == []
    assert [p.id for p in reg.query(namespace_prefix="robonix/service")] == ["mapping"]
    by_contract = reg.query(contract_id=ODOM)
    assert [p.id for p in by_contract] == ["chassis", "mapping"]
    assert all(len(p.capabilities) == 1 and p.capabilities[0].contract_id == ODOM for p in by_contract)
    # the transport filter empties mapping's list but does not drop it (robonix behaviour)
    ros = reg.query(contract_id=ODOM, transport=R)
    assert [(p.id, len(p.capabilities)) for p in ros] == [("chassis", 1), ("mapping", 0)]
    assert [len(p.capabilities) for p in reg.query(id="chassis", transport=R)] == [2]
    # unknown enum values mean "no filter"
    assert len(reg.query(kind=42, transport=42)) == 3
    assert reg.query(contract_id=ODOM, kind=Kind.SKILL) == []


# --------------------------------------------------------------------------- connect / disconnect


def test_connect_rules(reg: Registry) -> None:
    _populate(reg)
    for kwargs, field in (
        ({"consumer_id": ""}, "consumer_id"),
        ({"provider_id": ""}, "provider_id"),
        ({"contract_id": ""}, "contract_id"),
    ):
        args = {"consumer_id": "nav", "provider_id": "chassis", "contract_id": ODOM, "transport": R} | kwargs
        with err("INVALID_ARGUMENT", field):
            reg.connect(**args)
    with err("INVALID_ARGUMENT", "transport"):
        reg.connect("nav", "chassis", ODOM, Transport.UNSPECIFIED)
    with err("NOT_FOUND", "provider_id"):
        reg.connect("nav", "ghost", ODOM, R)
    with err("NOT_FOUND", "contract_id"):
        reg.connect("nav", "chassis", "robonix/unknown/contract", R)
    with err("NOT_FOUND", "contract_id"):
        reg.connect("nav", "chassis", ODOM, G)
    ch = reg.connect("nav", "chassis", ODOM, R)
    assert re.fullmatch(r"ch-[0-9a-f]{32}", ch.channel_id)
    assert ch.endpoint == "/odom"
    assert ch.params == Ros2Params("reliable")
    assert reg.channel_count("chassis") == 1
    assert reg.disconnect(ch.channel_id) is True
    assert reg.disconnect(ch.channel_id) is False
    reg.set_state("chassis", LifecycleState.TERMINATED)
    # robonix's atlas still opens a channel to a TERMINATED provider (the endpoints stay until GC)
    late = reg.connect("nav", "chassis", ODOM, R)
    assert late.endpoint == "/odom"
    assert reg.channel_count("chassis") == 1


# --------------------------------------------------------------------------- eviction / GC


def test_eviction_and_gc(reg: Registry, clock: FakeClock) -> None:
    _populate(reg)
    reg.connect("nav", "chassis", ODOM, R)
    reg.connect("nav", "mapping", ODOM, G)
    clock.advance_ms(800)
    reg.heartbeat("mapping")
    clock.advance_ms(400)  # chassis and skill idle 1200 ms > 1000, mapping 400 ms
    evicted, removed = reg.sweep()
    assert sorted(evicted) == ["chassis", "skill"]
    assert removed == []
    [c] = reg.query(id="chassis")
    assert c.state == LifecycleState.TERMINATED
    assert c.state_detail == "heartbeat lapsed > 1000ms"
    assert c.capabilities  # kept for diagnosis until GC
    assert reg.channel_count("chassis") == 0
    assert reg.channel_count("mapping") == 1
    # a heartbeat does not revive a TERMINATED provider
    reg.heartbeat("skill")
    assert reg.sweep() == ([], [])
    assert reg.query(id="skill")[0].state == LifecycleState.TERMINATED
    # GC after timeout + gc (1000 + 5000) since the last heartbeat
    clock.advance_ms(4900)
    assert reg.sweep()[1] == ["chassis"]
    assert reg.query(id="chassis") == []
    # the same id registers again with a new registration id
    chassis(reg)
    assert reg.query(id="chassis")[0].state == LifecycleState.REGISTERED


def test_eviction_disabled_with_zero_timeout(catalogue: Catalogue, clock: FakeClock) -> None:
    reg = Registry(catalogue, heartbeat_timeout_ms=0, clock=clock)
    chassis(reg)
    clock.advance_ms(10**9)
    assert reg.sweep() == ([], [])
    assert reg.query()[0].state == LifecycleState.REGISTERED


# --------------------------------------------------------------------------- contracts & snapshot


def test_contract_lookup(reg: Registry) -> None:
    with err("INVALID_ARGUMENT", "contract_id"):
        reg.query_contract("")
    assert reg.query_contract("robonix/nope") is None
    d = reg.query_contract(ODOM)
    assert d is not None
    assert d.io_msg_type == "nav_msgs/msg/Odometry"
    ids = [c.id for c in reg.list_contracts("robonix/service/map/")]
    assert ids == sorted(ids)
    assert len(ids) >= 10
    assert all(i.startswith("robonix/service/map/") for i in ids)
    assert len(reg.list_contracts()) == len(reg.catalogue) >= 31


def test_snapshot_is_json(reg: Registry) -> None:
    _populate(reg)
    reg.connect("nav", "chassis", ODOM, R)
    snap = json.loads(json.dumps(reg.snapshot()))
    assert {p["id"] for p in snap["providers"]} == {"chassis", "mapping", "skill"}
    assert {"provider_id": "chassis", "contract_id": ODOM}.items() <= snap["capabilities"][0].items()
    assert snap["channels"][0]["endpoint"] == "/odom"
    assert snap["contracts"] == len(reg.catalogue)


# --------------------------------------------------------------------------- ROS 2 names


@pytest.mark.parametrize(
    "name",
    [
        "/odom",
        "odom",
        "/rbnx/robonix/primitive/chassis/odom/t1a2b3c4d",
        "~",
        "~/scan",
        "/a_b/c1",
        "_x",
        "/A/B9",
    ],
)
def test_valid_ros2_names(name: str) -> None:
    assert is_valid_ros2_name(name)


@pytest.mark.parametrize(
    "name",
    [
        "",
        "/",
        "~/",
        "/odom/",
        "//odom",
        "/1odom",
        "/a/9b",
        "/rbnx/robonix.primitive.chassis.odom/1a2b3c4d",  # robonix's dotted mint
        "/odom__1a2b3c4d",  # robonix's collision rewrite
        "/odom_",
        "/od om",
        "/odom~",
        "/a/~/b",
        "/{node}/x",
    ],
)
def test_invalid_ros2_names(name: str) -> None:
    assert not is_valid_ros2_name(name)


def test_mint_and_rewrite_always_valid() -> None:
    for cid in (ODOM, "robonix/service/map/occupancy_grid", "weird//9lives/a-b.c/__x__", "3d/scan"):
        for _ in range(50):
            assert is_valid_ros2_name(mint_ros2_endpoint(cid)), cid
    for proposed in ("/odom", "/odom_", "scan", "/a/b_c"):
        for _ in range(50):
            out = rewrite_ros2_endpoint(proposed)
            assert is_valid_ros2_name(out), out
            assert out != proposed, out
