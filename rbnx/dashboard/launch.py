"""Start the live dashboard in the background: for `rbnx dashboard` and the ``--dashboard`` option of
`rbnx boot` / `rbnx demo`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

DEFAULT_PORT = 8765


def atlas_of_deploy(deploy: Path) -> Callable[[], str | None]:
    """The atlas address of a (possibly still starting) `rbnx boot` of ``deploy``, read from its state file."""
    from rbnx.boot.deployment import StateNotFound, locate_state
    from rbnx.boot.statefile import read_state

    def atlas() -> str | None:
        try:
            return (read_state(locate_state(deploy)) or {}).get("atlas")
        except StateNotFound:  # not written yet: the boot is still starting
            return None

    return atlas


def check_port(port: int) -> str | None:
    return None if 0 <= port <= 65535 else f"--port: must be 0..65535, got {port}"


def start_background(atlas: str | Callable[[], str | None], port: int, domain_id: int | None = None,
                     host: str = "127.0.0.1") -> Any:
    """A running DashboardServer (serving from a thread); ``stop()`` it when done. OSError if the port is taken."""
    from rbnx.dashboard.server import DashboardServer
    from rbnx.dashboard.state import LiveState

    server = DashboardServer(LiveState(atlas, domain_id), host, port)
    server.start()
    return server
