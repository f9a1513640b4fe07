"""Property-based abuse of every unary gRPC contract the deployment serves and of every atlas RPC:
hypothesis fills every field of each request message with hostile values, mostly sent with the
deployment's token (as a legitimate client would) and sometimes without. Every reply must be a valid
response or a clear status (a client-error code, a message of at most 1024 characters); never INTERNAL,
UNKNOWN or a dead server."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import grpc
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robonix_api import auth
from robonix_api.contracts import load_catalogue
from robonix_api.proto_gen import atlas_pb2, robonix_contracts_pb2

from .deployment import Deployment
from .strategies import fuzz_settings, requests

pytestmark = pytest.mark.integration

CLEAR = {grpc.StatusCode.INVALID_ARGUMENT, grpc.StatusCode.FAILED_PRECONDITION, grpc.StatusCode.NOT_FOUND,
         grpc.StatusCode.ALREADY_EXISTS, grpc.StatusCode.OUT_OF_RANGE, grpc.StatusCode.PERMISSION_DENIED,
         grpc.StatusCode.UNAUTHENTICATED, grpc.StatusCode.RESOURCE_EXHAUSTED, grpc.StatusCode.UNIMPLEMENTED}
SKIP = {"robonix/lifecycle/driver"}  # driven in test_abuse_driver (commands change the provider's state)
#: Mostly as a token holder (so the handlers behind the token check are exercised), sometimes without.
WITH_TOKEN = st.sampled_from([True, True, True, False])
EXAMPLES = fuzz_settings(60)


def _call(channel: grpc.Channel, path: str, req_cls: Any, resp_cls: Any) -> Callable[[Any], Any]:
    return channel.unary_unary(path, request_serializer=req_cls.SerializeToString,
                               response_deserializer=resp_cls.FromString)


def check_reply(fn: Callable[[Any], Any], req: Any, what: str, with_token: bool = True) -> None:
    try:
        fn(req, timeout=60, metadata=auth.metadata() if with_token else None)
    except grpc.RpcError as exc:
        code, details = exc.code(), exc.details() or ""
        assert code in CLEAR, f"{what}: {code.name}: {details[:500]}"
        assert details, f"{what}: {code.name} with a {len(details)}-char message"
        assert len(details) <= 1024, f"{what}: {code.name} with a {len(details)}-char message"


def fuzz(dep: Deployment, strategy: st.SearchStrategy[Any], fn: Callable[[Any], Any], label: str) -> None:
    """Run ``fn`` on hypothesis-drawn requests and check every reply."""

    @EXAMPLES
    @given(req=strategy, with_token=WITH_TOKEN)
    def run(req: Any, with_token: bool) -> None:
        dep.count(label)
        check_reply(fn, req, label, with_token)

    run()


def contract_methods(dep: Deployment) -> list[tuple[str, str, str, Any, Any]]:
    """(provider, contract, path, request class, response class) for every unary gRPC contract served."""
    specs = {spec.service_name: spec for spec in load_catalogue().values()}
    out = []
    for provider, contract in dep.capabilities("grpc"):
        if contract in SKIP:
            continue
        spec = next((s for s in specs.values() if s.id == contract), None)
        if spec is None:
            continue
        service = robonix_contracts_pb2.DESCRIPTOR.services_by_name.get(spec.service_name)
        if service is None:
            continue
        method = service.methods_by_name[spec.method_name]
        if method.client_streaming or method.server_streaming:
            continue
        req_cls = _message_class(method.input_type)
        resp_cls = _message_class(method.output_type)
        out.append((provider, contract, spec.grpc_path, req_cls, resp_cls))
    return out


def _message_class(desc: Any) -> Any:
    from google.protobuf import message_factory

    return message_factory.GetMessageClass(desc)


def test_every_contract_request_field(deployment: Deployment) -> None:
    methods = contract_methods(deployment)
    assert len(methods) >= 20, [m[1] for m in methods]
    bait = [str(deployment.bait), str(deployment.bait / "sub"), "../bait", "../../bait/sub"]
    channels: dict[str, grpc.Channel] = {}
    try:
        for provider, contract, path, req_cls, resp_cls in methods:
            endpoint = deployment.endpoint(provider, contract)
            ch = channels.setdefault(endpoint, grpc.insecure_channel(endpoint))
            fuzz(deployment, requests(req_cls, bait), _call(ch, path, req_cls, resp_cls), f"gRPC {contract}")
            deployment.assert_alive()
    finally:
        for ch in channels.values():
            ch.close()


def test_every_atlas_rpc_field(deployment: Deployment) -> None:
    service = atlas_pb2.DESCRIPTOR.services_by_name["Atlas"]
    live = set(deployment.pids)

    def harmless(req: Any) -> bool:
        """Leave the deployment's own registrations alone (part A's token guards them)."""
        return not any(getattr(req, f, None) in live for f in ("id", "provider_id"))

    with grpc.insecure_channel(deployment.atlas) as ch:
        for method in service.methods:
            req_cls, resp_cls = _message_class(method.input_type), _message_class(method.output_type)
            fn = _call(ch, f"/{service.full_name}/{method.name}", req_cls, resp_cls)
            fuzz(deployment, requests(req_cls).filter(harmless), fn, f"atlas {method.name}")
            deployment.assert_alive()
    assert set(deployment.states()) == live
