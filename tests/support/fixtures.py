"""Pytest fixtures shared by the integration-test directories; a directory's conftest imports ``atlas``
and builds its ``procs`` fixture with ``procs_fixture()``."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest

from .procs import Proc, stop_all


@pytest.fixture(scope="module")
def atlas() -> Iterator[str]:
    """An in-process atlas on a loopback port of the OS's choosing; its address."""
    from atlas.server import AtlasServer

    server = AtlasServer(listen="127.0.0.1:0", heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    address = server.start()
    try:
        yield address
    finally:
        server.stop()


def procs_fixture(cls: type[Proc] = Proc, *, newest_first: bool = True, clean_exit: bool = False) -> Any:
    """A module-scoped ``procs`` fixture: ``procs(cmd, name, **env)`` starts a ``cls`` child (log in a temp
    dir); at module end every child is stopped by PID (newest first unless told otherwise) and none may be
    left behind (see ``stop_all``)."""

    @pytest.fixture(scope="module")
    def procs(atlas: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[..., Proc]]:
        started: list[Proc] = []

        def make(cmd: list[str], name: str, **env: str) -> Proc:
            p = cls(cmd, atlas, name, tmp_path_factory.mktemp(name) / "provider.log", env)
            started.append(p)
            return p

        yield make
        stop_all(reversed(started) if newest_first else started, clean_exit=clean_exit)

    return procs
