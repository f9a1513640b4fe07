"""An MCP tool server whose port and tools exist at once but whose server stack loads when needed.

Importing the official ``mcp`` package (and uvicorn/starlette) costs about a second of CPU per process.
Three providers and the boot tool doing that while a deployment boots on a two-core robot computer delay
every ``CMD_INIT`` on the critical path. So a provider binds and listens on its MCP port immediately and
declares its tools (schemas come from :mod:`robonix_api.mcp_tools`, no ``mcp`` import); the stack is
loaded on a background thread when the first client connects (it waits in the listen backlog, a second
or so at most) or ``ROBONIX_MCP_PRELOAD_S`` seconds after start (default 5, after a typical boot),
whichever comes first. ``ROBONIX_MCP_PRELOAD_S=0`` loads it at once.
"""

from __future__ import annotations

import logging
import os
import select
import socket
import threading
import time
from collections.abc import Callable
from typing import Any

from robonix_api.netutil import bind_listener

log = logging.getLogger(__name__)

DEFAULT_PRELOAD_S = 5.0
MAX_PRELOAD_S = 300.0


def preload_delay() -> float:
    """``ROBONIX_MCP_PRELOAD_S`` in [0, 300], default 5; a bad value is an error naming the variable."""
    raw = os.environ.get("ROBONIX_MCP_PRELOAD_S", "").strip()
    if not raw:
        return DEFAULT_PRELOAD_S
    try:
        value = float(raw)
    except ValueError:
        raise ValueError(f"ROBONIX_MCP_PRELOAD_S must be a number of seconds, got {raw[:40]!r}") from None
    if not 0.0 <= value <= MAX_PRELOAD_S:
        raise ValueError(f"ROBONIX_MCP_PRELOAD_S must be within [0, {MAX_PRELOAD_S:g}], got {value:g}")
    return value


class DeferredMcpServer:
    """Listening socket now, server later. ``build(sock)`` imports the stack, serves on ``sock`` and
    returns an object with ``stop()`` (e.g. a started :class:`robonix_api.mcp_server.McpToolServer`)."""

    def __init__(self, name: str, host: str, build: Callable[[socket.socket], Any],
                 preload_s: float | None = None) -> None:
        self._name = name
        self._build = build
        self._preload_s = preload_delay() if preload_s is None else preload_s
        self._sock = bind_listener(host)
        self.port: int = self._sock.getsockname()[1]
        self._server: Any = None
        self._stopped = threading.Event()
        self._loaded = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._wait_then_load, name=f"mcp-load-{name}", daemon=True)

    def start(self) -> int:
        """Begin waiting for the first client or the preload time; returns the port (listening already)."""
        self._thread.start()
        return self.port

    @property
    def loaded(self) -> bool:
        """Whether the MCP stack has been loaded (first client or preload timer)."""
        return self._loaded.is_set()

    def wait_loaded(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` for the MCP stack to load; True once it has."""
        return self._loaded.wait(timeout_s)

    def _wait_then_load(self) -> None:
        deadline = time.monotonic() + self._preload_s
        while not self._stopped.is_set():
            left = deadline - time.monotonic()
            if left <= 0:
                break
            try:
                readable, _, _ = select.select([self._sock], [], [], min(left, 0.5))
            except (OSError, ValueError):  # closed by stop()
                return
            if readable:
                break
        with self._lock:
            if self._stopped.is_set():
                return
            t0 = time.monotonic()
            try:
                self._server = self._build(self._sock)
            except Exception:
                log.exception("MCP server of %s failed to start; its tools stay unreachable", self._name)
                return
            log.debug("MCP server of %s loaded in %.2f s", self._name, time.monotonic() - t0)
            self._loaded.set()

    def stop(self) -> None:
        """Stop serving (or cancel the pending load) and release the port."""
        self._stopped.set()
        with self._lock:
            server, self._server = self._server, None
        if server is not None:
            server.stop()  # closes the socket it took over
        else:
            self._sock.close()
        self._thread.join(5.0)
