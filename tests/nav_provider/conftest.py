"""Real processes for the navigation provider tests: an in-process atlas plus provider children.

Each child (nav provider, HAL, the stand-in map provider) is found through the atlas like any consumer
would, driven over its lifecycle Driver, and stopped by its own PID (SIGTERM, SIGKILL after a grace
period); the fixtures assert none is left behind. Deadlines are generous (shared 2-core machine).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from .procs import ACTIVATE, DEACTIVATE, HAL, INIT, MAP_PROVIDER, NAV, SHUTDOWN, Proc, alive, wait_until

__all__ = ["ACTIVATE", "DEACTIVATE", "HAL", "INIT", "MAP_PROVIDER", "NAV", "SHUTDOWN", "Proc", "wait_until"]


@pytest.fixture(scope="module")
def atlas() -> Iterator[str]:
    from atlas.server import AtlasServer

    server = AtlasServer(listen="127.0.0.1:0", heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    address = server.start()
    try:
        yield address
    finally:
        server.stop()


@pytest.fixture(scope="module")
def procs(atlas: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[..., Proc]]:
    """``procs(cmd, name, **env)`` starts a provider child; all are stopped (by PID) at module end."""
    started: list[Proc] = []

    def make(cmd: list[str], name: str, **env: str) -> Proc:
        p = Proc(cmd, atlas, name, tmp_path_factory.mktemp(name) / "provider.log", env)
        started.append(p)
        return p

    yield make
    for p in started:
        if p.proc.poll() is None:
            p.stop()
        assert not alive(p.proc.pid)
