"""Wire compatibility: call the atlas with hand-encoded protobuf bytes built from the field numbers in
spec §1.3 (not from our generated stubs), and decode the replies the same way.

A robonix client written against the published atlas.proto sends exactly these bytes, so if our
proto drifts (a renumbered field, a renamed service), this test fails even if our stubs agree."""

from __future__ import annotations

import grpc
from support.wire import decode, f_bytes, f_str, f_varint, one

# --------------------------------------------------------------------------- spec numbers (§1.2/§1.3)

KIND_PRIMITIVE = 1
TRANSPORT_ROS2 = 2
STATE_REGISTERED, STATE_INACTIVE = 1, 2
SERVICE = "/robonix.atlas.Atlas"


def call(channel: grpc.Channel, method: str, request: bytes) -> bytes:
    fn = channel.unary_unary(f"{SERVICE}/{method}", request_serializer=None, response_deserializer=None)
    return fn(request, timeout=10)


def test_query_with_hand_built_bytes(atlas_server, uid: str) -> None:
    pid = f"wire-{uid}"
    contract = "robonix/primitive/chassis/odom"
    with grpc.insecure_channel(atlas_server.address, options=[("grpc.enable_http_proxy", 0)]) as ch:
        # RegisterRequest{id=1, namespace=2}
        reply = decode(call(ch, "RegisterPrimitive", f_str(1, pid) + f_str(2, "robonix/primitive/chassis")))
        assert one(reply, 1) == pid.encode()  # RegisterResponse.id = 1

        # DeclareCapabilityRequest{provider_id=1, contract_id=2, transport=3, endpoint=4,
        #   params=5: TransportParams{ros2=2: Ros2Params{qos_profile=1}}}
        params = f_bytes(2, f_str(1, "reliable"))
        req = f_str(1, pid) + f_str(2, contract) + f_varint(3, TRANSPORT_ROS2) + f_str(4, f"/odom_{uid}")
        reply = decode(call(ch, "DeclareCapability", req + f_bytes(5, params)))
        assert one(reply, 1) == f"/odom_{uid}".encode()  # DeclareCapabilityResponse.endpoint = 1

        # QueryRequest{kind=1, id=2, contract_id=3, transport=4, namespace_prefix=5}
        req = (
            f_varint(1, KIND_PRIMITIVE)
            + f_str(2, pid)
            + f_str(3, contract)
            + f_varint(4, TRANSPORT_ROS2)
            + f_str(5, "robonix/")
        )
        providers = decode(call(ch, "Query", req)).get(1, [])  # QueryResponse.providers = 1
        assert len(providers) == 1
        prov = decode(providers[0])
        # CapabilityProvider{id=1, kind=2, namespace=3, last_heartbeat_ms=5, state=6, capabilities=8}
        assert one(prov, 1) == pid.encode()
        assert one(prov, 2) == KIND_PRIMITIVE
        assert one(prov, 3) == b"robonix/primitive/chassis"
        assert one(prov, 5) > 1_600_000_000_000  # epoch milliseconds
        assert one(prov, 6) == STATE_INACTIVE  # never pushed + a non-driver capability
        assert len(one(prov, 10, b"")) == 36  # registration_id (UNCONFIRMED number 10): a uuid4 string
        [cap_bytes] = prov[8]
        cap = decode(cap_bytes)
        # Capability{provider_id=1, provider_kind=2, contract_id=3, transport=4, params=5}
        assert one(cap, 1) == pid.encode()
        assert one(cap, 2) == KIND_PRIMITIVE
        assert one(cap, 3) == contract.encode()
        assert one(cap, 4) == TRANSPORT_ROS2
        assert decode(decode(one(cap, 5))[2][0]) == {1: [b"reliable"]}

        # an empty QueryRequest (all defaults) is an empty byte string and lists everyone
        everyone = [decode(p) for p in decode(call(ch, "Query", b"")).get(1, [])]
        assert pid.encode() in [one(p, 1) for p in everyone]

        # UnregisterRequest{id=1} -> UnregisterResponse{was_present=1}
        assert decode(call(ch, "Unregister", f_str(1, pid))) == {1: [1]}
        assert decode(call(ch, "Unregister", f_str(1, pid))) == {}  # false is not encoded in proto3


def test_query_contract_not_found_bytes(atlas_server) -> None:
    with grpc.insecure_channel(atlas_server.address, options=[("grpc.enable_http_proxy", 0)]) as ch:
        # QueryContractResponse{contract=1 (present but empty), found=2 (false: absent)}
        assert decode(call(ch, "QueryContract", f_str(1, "robonix/nope"))) == {1: [b""]}
        reply = decode(call(ch, "QueryContract", f_str(1, "robonix/lifecycle/driver")))
        assert one(reply, 2) == 1
        desc = decode(one(reply, 1))
        # ContractDescriptor{id=1, kind=3, mode=4, io_srv_type=6, srv_request_fields=9, cross_namespace=12}
        assert one(desc, 1) == b"robonix/lifecycle/driver"
        assert one(desc, 3) == 2
        assert one(desc, 4) == b"rpc"
        assert one(desc, 6) == b"lifecycle/srv/Driver"
        assert one(desc, 12) == 1
        first_field = decode(desc[9][0])  # FieldSpec{name=1, type_name=2, is_primitive=3}
        assert (
            one(first_field, 1) == b"command"
        )
        assert (
            one(first_field, 2) == b"uint8"
        )
        assert (
            one(first_field, 3) == 1
        )
