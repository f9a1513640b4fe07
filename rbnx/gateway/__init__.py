"""Agents in charge: the deployment's MCP gateway and the lifecycle verbs it (and `rbnx lifecycle`) offers.

``rbnx boot`` serves :class:`Gateway` next to the atlas, prints its URL and records it in the boot state
file (``gateway``), where ``rbnx tools`` and ``rbnx lifecycle`` find it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from rbnx.gateway.control import ControlError, Entry, LifecycleControl, merge_patch
from rbnx.gateway.server import Gateway


def start_for_boot(atlas_addr: str, runners: Iterable[Any], shutdown_all: Callable[[], None],
                   driver_timeout: float) -> Gateway:
    """The gateway of one ``rbnx boot``: its entries are the boot's runners (``.entry``, ``.restarts``)."""
    runners = list(runners)
    by_name = {r.name: r for r in runners}
    entries = [Entry(r.entry.name, r.entry.kind, dict(r.entry.config), getattr(r.entry, "autostart", True))
               for r in runners]
    control = LifecycleControl(atlas_addr, entries, driver_timeout=driver_timeout, shutdown_all=shutdown_all,
                               restarts=lambda name: int(getattr(by_name.get(name), "restarts", 0) or 0))
    gw = Gateway(atlas_addr, control)
    gw.start()
    return gw


__all__ = ["ControlError", "Entry", "Gateway", "LifecycleControl", "merge_patch", "start_for_boot"]
