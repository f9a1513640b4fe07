"""Keeps the unit half honest: a test under tests/unit that starts a process, opens a network socket,
creates a DDS participant or serves gRPC fails at once with a message saying so. Such a test belongs in
tests/integration/<package> (see tests/conftest.py for the layout). Unix-domain sockets (asyncio's
self-pipe) and MuJoCo in the test's own process stay allowed."""

from __future__ import annotations

import socket
import subprocess
from typing import Any

import grpc
import pytest
from cyclonedds.domain import DomainParticipant


class NotAUnitTest(AssertionError):
    """Raised when a unit test does what only integration tests may do."""


def _refuse(what: str) -> None:
    raise NotAUnitTest(f"a unit test may not {what}; move this test to tests/integration/<package>")


@pytest.fixture(autouse=True)
def _no_processes_sockets_dds_or_servers(monkeypatch: pytest.MonkeyPatch) -> None:
    real_socket_init = socket.socket.__init__

    def socket_init(self: socket.socket, family: int = -1, type: int = -1, proto: int = -1,
                    fileno: int | None = None) -> None:
        if fileno is None and family != socket.AF_UNIX:
            _refuse("open a network socket")
        real_socket_init(self, family, type, proto, fileno)

    def refuse(what: str) -> Any:
        def guard(*_args: Any, **_kwargs: Any) -> Any:
            _refuse(what)
        return guard

    monkeypatch.setattr(socket.socket, "__init__", socket_init)
    monkeypatch.setattr(subprocess.Popen, "__init__", refuse("start a process"))
    monkeypatch.setattr(grpc, "server", refuse("serve gRPC"))
    monkeypatch.setattr(DomainParticipant, "__init__", refuse("create a DDS participant"))
