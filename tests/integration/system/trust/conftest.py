"""Shared pieces of the trust tests: an in-process atlas with (or without) a deployment token, raw
stubs that send exactly the metadata a test chooses (no token unless asked), and for the file, bounds
and MCP-session tests a module-scoped atlas (``atlas``) with provider children (``procs``) stopped by
PID at module end (see tests/support/fixtures.py)."""

from __future__ import annotations

from collections.abc import Iterator

import grpc
import pytest
from support.fixtures import atlas, procs_fixture

from atlas.server import AtlasServer
from robonix_api.auth import METADATA_KEY, TOKEN_ENV
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc

TOKEN = "trust-test-token-0123456789abcdef"
procs = procs_fixture()
__all__ = ["atlas", "procs"]


@pytest.fixture(autouse=True)
def _no_ambient_token(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each test decides itself whether this process holds the token; whatever it sets is undone after
    (setenv first, so monkeypatch records the variable and restores it even when it was absent)."""
    monkeypatch.setenv(TOKEN_ENV, "placeholder")
    monkeypatch.delenv(TOKEN_ENV)


@pytest.fixture
def token_atlas() -> Iterator[AtlasServer]:
    with AtlasServer("127.0.0.1:0", token=TOKEN, heartbeat_timeout_ms=0) as server:
        yield server


@pytest.fixture
def open_atlas() -> Iterator[AtlasServer]:
    with AtlasServer("127.0.0.1:0", heartbeat_timeout_ms=0) as server:
        yield server


def raw_stub(address: str) -> tuple[grpc.Channel, atlas_pb2_grpc.AtlasStub]:
    ch = grpc.insecure_channel(address, options=[("grpc.enable_http_proxy", 0)])
    return ch, atlas_pb2_grpc.AtlasStub(ch)


def md(token: str | None = TOKEN) -> list[tuple[str, str]] | None:
    return [(METADATA_KEY, token)] if token is not None else None


def register(stub: atlas_pb2_grpc.AtlasStub, pid: str, namespace: str, token: str | None = TOKEN) -> str:
    return stub.RegisterService(atlas_pb2.RegisterRequest(id=pid, namespace=namespace), timeout=10,
                                metadata=md(token)).id


def declare_grpc(stub: atlas_pb2_grpc.AtlasStub, pid: str, contract: str, endpoint: str,
                 token: str | None = TOKEN) -> str:
    req = atlas_pb2.DeclareCapabilityRequest(provider_id=pid, contract_id=contract,
                                             transport=atlas_pb2.TRANSPORT_GRPC, endpoint=endpoint)
    req.params.grpc.service_name = "RobonixServiceNavigationNavigate"
    req.params.grpc.method = "Navigate"
    return stub.DeclareCapability(req, timeout=10, metadata=md(token)).endpoint
