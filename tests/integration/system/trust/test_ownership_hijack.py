"""Ownership of a provider id: the hijack of issue 17 (Register ``nav2`` with a fake endpoint, foreign
Unregister / SetLifecycleState(TERMINATED) / Declare) is refused with a token; without one (robonix's
takeover) the real provider notices its registration was replaced, says so and takes its id back."""

from __future__ import annotations

import logging
from collections.abc import Iterator

import grpc
import pytest
from support.procs import wait_until

from atlas.server import AtlasServer
from robonix_api import Ok, Service
from robonix_api.atlas_client import AtlasClient
from robonix_api.auth import TOKEN_ENV
from robonix_api.proto_gen import atlas_pb2

from .conftest import TOKEN, declare_grpc, raw_stub, register

NAV = "robonix/service/navigation/navigate"


@pytest.fixture
def fast_heartbeat(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROBONIX_HEARTBEAT_PERIOD_S", "0.2")
    for name in ("RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED", "ROBONIX_ADVERTISE_HOST", "ROBONIX_PROVIDER_BIND_HOST"):
        monkeypatch.delenv(name, raising=False)


@pytest.fixture
def nav2_factory(fast_heartbeat: None) -> Iterator[object]:
    made: list[Service] = []

    def make(address: str) -> Service:
        svc = Service("nav2", "robonix/service/navigation", atlas=address)
        svc.on_init(lambda cfg: Ok())
        made.append(svc)
        return svc.run_in_thread()

    yield make
    for svc in made:
        svc.stop()


def _record(address: str, pid: str) -> atlas_pb2.CapabilityProvider:
    ch, stub = raw_stub(address)
    with ch:
        (p,) = stub.Query(atlas_pb2.QueryRequest(id=pid), timeout=5).providers
    return p


def test_hijack_and_foreign_changes_refused_with_token(token_atlas: AtlasServer, nav2_factory: object,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(TOKEN_ENV, TOKEN)  # the provider is a child of the deployment
    svc = nav2_factory(token_atlas.address)  # type: ignore[operator]
    before = _record(token_atlas.address, "nav2")
    ch, stub = raw_stub(token_atlas.address)
    with ch:
        for attempt in (
            lambda: register(stub, "nav2", "robonix/service/navigation", token=None),
            lambda: declare_grpc(stub, "nav2", NAV, "127.0.0.1:6666", token=None),
            lambda: stub.Unregister(atlas_pb2.UnregisterRequest(id="nav2"), timeout=5),
            lambda: stub.SetLifecycleState(atlas_pb2.SetLifecycleStateRequest(
                id="nav2", state=atlas_pb2.STATE_TERMINATED, detail="spoofed"), timeout=5),
        ):
            with pytest.raises(grpc.RpcError) as err:
                attempt()
            assert err.value.code() == grpc.StatusCode.UNAUTHENTICATED
    after = _record(token_atlas.address, "nav2")
    assert after.registration_id == before.registration_id
    assert after.state == before.state != atlas_pb2.STATE_TERMINATED
    assert "robonix/lifecycle/driver" in {c.contract_id for c in after.capabilities}
    assert svc.registration_replaced == 0
    assert NAV not in {c.contract_id for c in after.capabilities}  # the fake declare left nothing


def test_provider_notices_its_registration_was_replaced(open_atlas: AtlasServer, nav2_factory: object,
                                                        caplog: pytest.LogCaptureFixture) -> None:
    """robonix's atlas semantics (no token): the takeover happens, but the real nav2 stops heartbeating a
    record that is no longer its own, logs it loudly and registers again with its real endpoints."""
    svc = nav2_factory(open_atlas.address)  # type: ignore[operator]
    caplog.set_level(logging.ERROR, logger="robonix_api.provider")
    ch, stub = raw_stub(open_atlas.address)
    with ch:
        register(stub, "nav2", "robonix/service/navigation", token=None)  # the hijack
        declare_grpc(stub, "nav2", NAV, "127.0.0.1:6666", token=None)
    wait_until(lambda: svc.registration_replaced >= 1, 30, "the provider to notice the takeover")
    with AtlasClient(open_atlas.address) as client:
        def restored() -> bool:
            (p,) = client.query(id="nav2")
            eps = {c.contract_id for c in p.capabilities}
            return NAV not in eps and "robonix/lifecycle/driver" in eps
        wait_until(restored, 30, "nav2's own record back on the atlas")
    assert any("REPLACED" in r.getMessage() for r in caplog.records)
