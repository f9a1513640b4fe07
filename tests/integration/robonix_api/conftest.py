"""Fixtures for the SDK and DDS tests: a recording fake atlas, the real atlas server, a DDS node per test and
the helper publisher process (tests/integration/robonix_api/dds_fixtures.py)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from support.fakes import FakeAtlas, FakeRpcError  # noqa: F401  (re-exported for the sdk tests)
from support.procs import wait_until  # noqa: F401  (re-exported for the sdk tests)

from .dds_fixtures import node, peer  # noqa: F401  (fixtures of the DDS tests)


@pytest.fixture
def fake_atlas() -> FakeAtlas:
    return FakeAtlas()


@pytest.fixture
def short_heartbeat(monkeypatch: pytest.MonkeyPatch) -> float:
    monkeypatch.setenv("ROBONIX_HEARTBEAT_PERIOD_S", "0.3")
    return 0.3


@pytest.fixture
def clean_env(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED", "ROBONIX_ADVERTISE_HOST",
                 "ROBONIX_PROVIDER_BIND_HOST"):
        monkeypatch.delenv(name, raising=False)


@pytest.fixture
def atlas_server(clean_env: None) -> Iterator[Any]:
    """A real in-process atlas on a free loopback port (skipped until atlas/server.py exists)."""
    server_mod = pytest.importorskip("atlas.server")
    server = server_mod.AtlasServer(listen="127.0.0.1:0", heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    server.start()
    try:
        yield server
    finally:
        server.stop()
