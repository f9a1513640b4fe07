"""Runs robonix-api 0.1.0rc1's own, unmodified ``ATLAS`` client against the atlas at $ROBONIX_ATLAS.

Executed by tests/compat/test_robonix_api_conformance.py with the python of a separate virtualenv that
has the real robonix-api wheel installed (not this project's SDK). It only drives the client and prints
one JSON object of what came back; the test makes the assertions.
"""

import json
import sys
import time

from robonix_api._lifecycle_internal import _set_lifecycle_state

import robonix_api
from robonix_api import ATLAS, GrpcParams, Kind, LifecycleState, McpParams, Ros2Params, Transport

LIDAR = "robonix/primitive/lidar/lidar"
GET_MODE = "robonix/service/map/get_mode"
GET_POSE = "robonix/service/map/get_pose"


def brief(providers):
    return sorted([p.id, p.kind.name, p.state.name, p.state_detail,
                   sorted([c.contract_id, c.transport.name] for c in p.capabilities)] for p in providers)


def main() -> None:
    out = {"sdk_file": robonix_api.__file__}
    out["register"] = [
        ATLAS.register_primitive("rbx_lidar", "robonix/primitive/lidar"),
        ATLAS.register_service("rbx_map", "robonix/service/map"),
        ATLAS.register_skill("rbx_skill", "robonix/skill/demo"),
    ]
    # robonix-api's positional order: (provider_id, contract_id, transport, endpoint, params, description)
    out["declare"] = [
        ATLAS.declare_capability("rbx_lidar", LIDAR, Transport.ROS2, "/rbx_scan", Ros2Params("best_effort"),
                                 "a test lidar"),
        ATLAS.declare_capability("rbx_map", GET_MODE, "grpc", "127.0.0.1:1",
                                 GrpcParams(service_name="RobonixServiceMapGetMode", method="GetMode")),
        ATLAS.declare_capability(provider_id="rbx_map", contract_id=GET_POSE, transport=Transport.MCP,
                                 endpoint="http://127.0.0.1:2/mcp/", params=McpParams('{"type": "object"}'),
                                 description="pose tool"),
    ]
    out["query_all"] = brief(ATLAS.query(namespace_prefix="robonix/"))
    out["query_primitives"] = brief(ATLAS.query_primitives())
    out["query_services"] = brief(ATLAS.query_services(contract_id=GET_MODE))
    out["query_skills"] = brief(ATLAS.query_skills())
    out["query_by_kind_str"] = [p.id for p in ATLAS.query(kind="primitive", transport="ros2")]
    caps = ATLAS.find_capability(contract_id=LIDAR)
    out["find"] = [[c.provider_id, c.provider_kind.name, c.transport.name, c.description,
                    getattr(c.params, "qos_profile", None)] for c in caps]
    uniq = ATLAS.find_unique_capability(contract_id=GET_POSE, transport=Transport.MCP)
    out["find_unique"] = [uniq.provider_id, uniq.params.input_schema_json, uniq.description]
    try:
        ATLAS.find_unique_capability(contract_id="robonix/none")
        out["find_unique_none"] = "no error"
    except ValueError as exc:
        out["find_unique_none"] = f"ValueError: {exc}"
    contract = ATLAS.query_contract(LIDAR)
    out["query_contract"] = [contract.id, contract.mode, contract.io_msg_type, Kind(contract.kind).name,
                             [f.name for f in contract.msg_fields][:3]]
    out["query_contract_missing"] = ATLAS.query_contract("robonix/none") is None
    out["list_contracts"] = sorted(c.id for c in ATLAS.list_contracts("robonix/service/map/"))

    ch = ATLAS.connect_capability(consumer_id="rbx_map", provider_id="rbx_lidar", contract_id=LIDAR,
                                  transport=Transport.ROS2)
    out["connect"] = [ch.endpoint, bool(ch.channel_id), type(ch.params).__name__,
                      getattr(ch.params, "qos_profile", None)]
    out["inspect_has_channel"] = any(c.get("channel_id") == ch.channel_id
                                     for c in ATLAS.inspect().get("channels", []))
    out["disconnect"] = [ATLAS.disconnect_capability(ch.channel_id), ATLAS.disconnect_capability(ch.channel_id)]
    with ATLAS.connect_capability(consumer_id="rbx_lidar", provider_id="rbx_map", contract_id=GET_MODE,
                                  transport="grpc") as ch2:
        out["connect_grpc"] = [ch2.endpoint, ch2.params.service_name, ch2.params.method, ch2.params.proto_file]
        chan_id = ch2.channel_id
    out["with_closed"] = not any(c.get("channel_id") == chan_id for c in ATLAS.inspect().get("channels", []))

    before = ATLAS.query(id="rbx_lidar")[0].last_heartbeat_ms
    time.sleep(0.05)
    ATLAS.heartbeat("rbx_lidar")
    out["heartbeat_advanced"] = ATLAS.query(id="rbx_lidar")[0].last_heartbeat_ms > before
    ATLAS.heartbeat("rbx_nobody")  # robonix-api swallows errors here
    thread = ATLAS.start_heartbeat("rbx_map", period_s=0.05)
    out["start_heartbeat"] = [type(thread).__name__, thread.daemon, thread.is_alive()]

    _set_lifecycle_state("rbx_lidar", LifecycleState.INACTIVE, "configured")
    _set_lifecycle_state("rbx_lidar", "active", "scanning")
    rec = ATLAS.query(id="rbx_lidar")[0]
    out["set_state"] = [rec.state.name, rec.state_detail]
    out["query_active"] = [p.id for p in ATLAS.query_primitives() if p.state == LifecycleState.ACTIVE]

    out["unregister"] = [ATLAS.unregister("rbx_lidar"), ATLAS.unregister("rbx_lidar"),
                         ATLAS.unregister("rbx_skill")]
    out["after_unregister"] = sorted(p.id for p in ATLAS.query(namespace_prefix="robonix/"))
    out["find_after_unregister"] = ATLAS.find_capability(contract_id=LIDAR) == []
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
