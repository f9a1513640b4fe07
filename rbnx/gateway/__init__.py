"""Agents in charge: the deployment's MCP gateway and the lifecycle verbs it (and `rbnx lifecycle`) offers.

``rbnx boot`` serves :class:`Gateway` next to the atlas (:class:`BootGateway`), prints its URL and records
it in the boot state file (``gateway``), where ``rbnx tools`` and ``rbnx lifecycle`` find it. The MCP
stack is imported only when a gateway is actually built (it takes a second or two on a busy machine).
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from rbnx.gateway.control import ControlError, Entry, LifecycleControl, merge_patch

if TYPE_CHECKING:
    from rbnx.gateway.server import Gateway


def __getattr__(name: str) -> Any:
    if name == "Gateway":
        from rbnx.gateway.server import Gateway

        return Gateway
    raise AttributeError(name)


def start_for_boot(atlas_addr: str, runners: Iterable[Any], shutdown_all: Callable[[], None],
                   driver_timeout: float) -> Gateway:
    """The gateway of one ``rbnx boot``: its entries are the boot's runners (``.entry``, ``.restarts``)."""
    from rbnx.gateway.server import Gateway

    runners = list(runners)
    by_name = {r.name: r for r in runners}
    entries = [Entry(r.entry.name, r.entry.kind, dict(r.entry.config), getattr(r.entry, "autostart", True))
               for r in runners]
    control = LifecycleControl(atlas_addr, entries, driver_timeout=driver_timeout, shutdown_all=shutdown_all,
                               restarts=lambda name: int(getattr(by_name.get(name), "restarts", 0) or 0))
    gw = Gateway(atlas_addr, control)
    gw.start()
    return gw


class BootGateway:
    """Builds and serves the boot's gateway on a thread, so the entries start booting meanwhile;
    ``on_ready(url)`` is called from that thread once it serves."""

    def __init__(self, atlas_addr: str, runners: Iterable[Any], shutdown_all: Callable[[], None],
                 driver_timeout: float, on_ready: Callable[[str], None]) -> None:
        self._args = (atlas_addr, list(runners), shutdown_all, driver_timeout)
        self._on_ready = on_ready
        self.gateway: Gateway | None = None
        self._thread = threading.Thread(target=self._run, name="gateway-start", daemon=True)

    def start(self) -> BootGateway:
        self._thread.start()
        return self

    def _run(self) -> None:
        try:
            self.gateway = start_for_boot(*self._args)
        except (RuntimeError, OSError, ImportError) as exc:
            print(f"rbnx boot: MCP gateway not started: {exc}", file=sys.stderr, flush=True)
            return
        self._on_ready(self.gateway.url)

    def stop(self) -> None:
        self._thread.join(60.0)
        if self.gateway is not None:
            self.gateway.stop()


__all__ = ["BootGateway", "ControlError", "Entry", "Gateway", "LifecycleControl", "merge_patch", "start_for_boot"]
