"""Thin, protobuf-level access to the atlas and to providers' Driver, for the CLI.

rbnx works on the raw messages (it prints them and needs every field), so it talks to the generated
stubs directly; every failure becomes an AtlasError with a one-line message.
"""

from __future__ import annotations

import contextlib
import json
import os
from dataclasses import dataclass
from typing import Any

import grpc

from robonix_api import auth, telemetry
from robonix_api.proto_gen import (
    atlas_pb2,
    atlas_pb2_grpc,
    lifecycle_pb2,
)

DRIVER_CONTRACT = "robonix/lifecycle/driver"
GRPC_OPTIONS = [("grpc.enable_http_proxy", 0)]
CONSUMER_ID = "rbnx"

CMD = lifecycle_pb2.Driver_Request
STATE_NAMES = {
    atlas_pb2.STATE_UNSPECIFIED: "unspecified",
    atlas_pb2.STATE_REGISTERED: "registered",
    atlas_pb2.STATE_INACTIVE: "inactive",
    atlas_pb2.STATE_ACTIVE: "active",
    atlas_pb2.STATE_ERROR: "error",
    atlas_pb2.STATE_TERMINATED: "terminated",
}
KIND_NAMES = {0: "unspecified", 1: "primitive", 2: "service", 3: "skill"}
TRANSPORT_NAMES = {0: "unspecified", 1: "grpc", 2: "ros2", 3: "mcp"}


def default_atlas() -> str:
    return os.environ.get("ROBONIX_ATLAS") or "127.0.0.1:50051"


class AtlasError(RuntimeError):
    """The atlas (or a provider) could not be reached or refused; str() is one line."""


def _describe(exc: grpc.RpcError, what: str, addr: str) -> AtlasError:
    code = exc.code() if hasattr(exc, "code") else None
    if code in (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.DEADLINE_EXCEEDED):
        return AtlasError(f"{what}: cannot reach {addr} ({code.name.lower()})")
    detail = exc.details() if hasattr(exc, "details") else str(exc)
    name = code.name if code else "error"
    return AtlasError(f"{what}: {name}: {detail}")


def params_text(params: atlas_pb2.TransportParams) -> str:
    kind = params.WhichOneof("kind")
    if kind == "grpc":
        return f"{params.grpc.service_name}/{params.grpc.method}".strip("/")
    if kind == "ros2":
        return f"qos={params.ros2.qos_profile}" if params.ros2.qos_profile else ""
    return ""


class Atlas:
    """A channel to one atlas with the handful of calls rbnx makes."""

    def __init__(self, addr: str, timeout: float = 5.0) -> None:
        self.addr = addr
        self.timeout = timeout
        self._ch = auth.channel(addr, options=GRPC_OPTIONS)  # carries $ROBONIX_DEPLOY_TOKEN when set
        self._stub = atlas_pb2_grpc.AtlasStub(self._ch)

    def close(self) -> None:
        self._ch.close()

    def __enter__(self) -> Atlas:
        return self

    def __exit__(self, *_: Any) -> None:
        self.close()

    def _call(self, name: str, req: Any, timeout: float | None = None) -> Any:
        try:
            return getattr(self._stub, name)(req, timeout=timeout or self.timeout)
        except grpc.RpcError as exc:
            raise _describe(exc, f"atlas {name}", self.addr) from None

    def query(self, kind: int = 0, id: str = "", contract_id: str = "", transport: int = 0,
              namespace_prefix: str = "") -> list[atlas_pb2.CapabilityProvider]:
        req = atlas_pb2.QueryRequest(kind=kind, id=id, contract_id=contract_id, transport=transport,
                                     namespace_prefix=namespace_prefix)
        return list(self._call("Query", req).providers)

    def provider(self, pid: str) -> atlas_pb2.CapabilityProvider | None:
        found = [p for p in self.query(id=pid) if p.id == pid]
        return found[0] if found else None

    def endpoint(self, provider_id: str, contract_id: str, transport: int) -> tuple[str, atlas_pb2.TransportParams]:
        """Connect to learn the endpoint, then close the channel at once (as robonix consumers do)."""
        resp = self._call("ConnectCapability", atlas_pb2.ConnectCapabilityRequest(
            consumer_id=CONSUMER_ID, provider_id=provider_id, contract_id=contract_id, transport=transport))
        with contextlib.suppress(grpc.RpcError):
            self._stub.DisconnectCapability(atlas_pb2.DisconnectCapabilityRequest(channel_id=resp.channel_id),
                                            timeout=self.timeout)
        return resp.endpoint, resp.params

    def list_contracts(self, prefix: str = "") -> list[atlas_pb2.ContractDescriptor]:
        return list(self._call("ListContracts", atlas_pb2.ListContractsRequest(namespace_prefix=prefix)).contracts)

    def inspect(self) -> dict[str, Any]:
        text = self._call("InspectAtlas", atlas_pb2.InspectAtlasRequest()).json
        try:
            return json.loads(text) if text else {}
        except json.JSONDecodeError:
            return {"raw": text}

    def ping(self, timeout: float = 1.0) -> bool:
        try:
            self._stub.ListContracts(atlas_pb2.ListContractsRequest(namespace_prefix="\x00"), timeout=timeout)
            return True
        except grpc.RpcError as exc:
            return exc.code() not in (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.DEADLINE_EXCEEDED)


def driver_capability(provider: atlas_pb2.CapabilityProvider) -> str | None:
    """The Driver contract a provider declared over gRPC (the shared one first, legacy `*/driver` next)."""
    grpc_caps = [c.contract_id for c in provider.capabilities if c.transport == atlas_pb2.TRANSPORT_GRPC]
    if DRIVER_CONTRACT in grpc_caps:
        return DRIVER_CONTRACT
    legacy = [c for c in grpc_caps if c.endswith("/driver")]
    return legacy[0] if legacy else None


@dataclass
class DriverReply:
    ok: bool
    state: str
    error: str


def driver_method_path(params: atlas_pb2.TransportParams | None) -> str:
    """The gRPC path of a declared Driver, from its GrpcParams.

    Our providers declare ``RobonixLifecycleDriver``; robonix-api packages declare their namespace's
    driver (``RobonixPrimitiveLidarDriver``); robonix's Rust components put the full name in
    ``service_name`` and the whole path in ``method``. All of them take the same Driver request.
    """
    g = params.grpc if params is not None and params.HasField("grpc") else None
    if g is None or not g.service_name:
        return DEFAULT_DRIVER_PATH
    if g.method.startswith("/"):
        return g.method
    service = g.service_name if "." in g.service_name else f"robonix.contracts.{g.service_name}"
    return f"/{service}/{g.method or 'Driver'}"


DEFAULT_DRIVER_PATH = "/robonix.contracts.RobonixLifecycleDriver/Driver"


class Driver:
    """A provider's lifecycle Driver at `host:port`; calls are futures so callers can abort them."""

    def __init__(self, endpoint: str, params: atlas_pb2.TransportParams | None = None) -> None:
        self.endpoint = endpoint.removeprefix("grpc://").removeprefix("http://")
        self.path = driver_method_path(params)
        self._ch = auth.channel(self.endpoint, options=GRPC_OPTIONS)
        self._call = self._ch.unary_unary(self.path, request_serializer=lifecycle_pb2.Driver_Request.SerializeToString,
                                          response_deserializer=lifecycle_pb2.Driver_Response.FromString)

    def call_async(self, command: int, config: dict[str, Any] | None, timeout: float) -> grpc.Future:
        req = lifecycle_pb2.Driver_Request(command=command, config_json="" if config is None else json.dumps(config))
        return self._call.future(req, timeout=timeout, metadata=telemetry.grpc_metadata() or None)

    def call(self, command: int, config: dict[str, Any] | None, timeout: float) -> DriverReply:
        return self.result(self.call_async(command, config, timeout))

    def result(self, fut: grpc.Future) -> DriverReply:
        try:
            r = fut.result()
        except grpc.FutureCancelledError:
            return DriverReply(False, "error", "cancelled")
        except grpc.RpcError as exc:
            return DriverReply(False, "error", str(_describe(exc, "Driver", self.endpoint)))
        return DriverReply(bool(r.ok), r.state, r.error)

    def close(self) -> None:
        self._ch.close()
