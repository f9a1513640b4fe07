"""Agents in charge: the deployment's MCP gateway and the lifecycle verbs it (and `rbnx lifecycle`) offers.

``rbnx boot`` serves :class:`Gateway` next to the atlas (:class:`BootGateway`), prints its URL and records
it in the boot state file (``gateway``), where ``rbnx tools`` and ``rbnx lifecycle`` find it. The MCP
stack is imported only when a gateway is actually served (it takes a second or two on a busy machine).
"""

from __future__ import annotations

import socket
import sys
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from rbnx.gateway.control import ControlError, Entry, LifecycleControl, merge_patch
from robonix_api.mcp_deferred import DeferredMcpServer
from robonix_api.mcp_tools import MCP_PATH

if TYPE_CHECKING:
    from rbnx.gateway.server import Gateway


def __getattr__(name: str) -> Any:
    if name == "Gateway":
        from rbnx.gateway.server import Gateway

        return Gateway
    raise AttributeError(name)


def start_for_boot(atlas_addr: str, runners: Iterable[Any], shutdown_all: Callable[[], None],
                   driver_timeout: float, sock: socket.socket | None = None) -> Gateway:
    """The gateway of one ``rbnx boot``: its entries are the boot's runners (``.entry``, ``.restarts``)."""
    from rbnx.gateway.server import Gateway

    runners = list(runners)
    by_name = {r.name: r for r in runners}
    entries = [Entry(r.entry.name, r.entry.kind, dict(r.entry.config), getattr(r.entry, "autostart", True))
               for r in runners]
    control = LifecycleControl(atlas_addr, entries, driver_timeout=driver_timeout, shutdown_all=shutdown_all,
                               restarts=lambda name: int(getattr(by_name.get(name), "restarts", 0) or 0))
    gw = Gateway(atlas_addr, control)
    gw.start(sock=sock)
    return gw


class BootGateway:
    """The boot's gateway: its port listens (and ``on_ready(url)`` is called) at once, while the MCP stack
    is loaded when the first agent connects or a few seconds later (:mod:`robonix_api.mcp_deferred`), so
    that second of CPU is not taken from the entries that are booting meanwhile."""

    def __init__(self, atlas_addr: str, runners: Iterable[Any], shutdown_all: Callable[[], None],
                 driver_timeout: float, on_ready: Callable[[str], None], host: str = "127.0.0.1") -> None:
        self._args = (atlas_addr, list(runners), shutdown_all, driver_timeout)
        self._on_ready = on_ready
        self._host = host
        self._deferred: DeferredMcpServer | None = None

    def start(self) -> BootGateway:
        self._deferred = DeferredMcpServer("gateway", self._host, self._build)
        port = self._deferred.start()
        self._on_ready(f"http://{self._host}:{port}{MCP_PATH}")
        return self

    def _build(self, sock: socket.socket) -> Gateway:
        try:
            return start_for_boot(*self._args, sock=sock)
        except (RuntimeError, OSError, ImportError) as exc:
            print(f"rbnx boot: MCP gateway not started: {exc}", file=sys.stderr, flush=True)
            raise

    def stop(self) -> None:
        if self._deferred is not None:
            self._deferred.stop()


__all__ = ["BootGateway", "ControlError", "Entry", "Gateway", "LifecycleControl", "merge_patch", "start_for_boot"]
