"""Accept both names of the Foxglove WebSocket protocol in front of the foxglove-sdk server.

foxglove-sdk (>= 0.x, and foxglove_bridge >= 3) only accepts the subprotocol ``foxglove.sdk.v1``; Lichtblick,
PlotJuggler, older Foxglove apps and most scripts offer ``foxglove.websocket.v1``. The two are the same
protocol under two names (Foxglove's stated position, foxglove/ros-foxglove-bridge#382), so this shim
accepts either on the public port and relays every frame unchanged, both ways, to the SDK server on a
private loopback port. One asyncio loop in one thread; ``stop`` closes it.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from typing import Any

SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
UPSTREAM_SUBPROTOCOL = "foxglove.sdk.v1"


class SubprotocolShim:
    """``ws://host:port`` speaking either subprotocol, relayed to ``upstream`` (a foxglove.sdk.v1 server)."""

    def __init__(self, upstream: str, host: str = "127.0.0.1", port: int = 0) -> None:
        self.upstream = upstream
        self.host = host
        self.port = port
        self._loop: asyncio.AbstractEventLoop | None = None
        self._server: Any = None
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Bind (OSError if the port is taken) and serve from a thread."""
        from websockets.asyncio.server import serve

        async def bind() -> Any:
            return await serve(self._relay, self.host, self.port, subprotocols=list(SUBPROTOCOLS),  # type: ignore[arg-type]
                               max_size=None, compression=None)

        loop = asyncio.new_event_loop()
        try:
            self._server = loop.run_until_complete(bind())
        except BaseException:
            loop.close()
            raise
        self.port = self._server.sockets[0].getsockname()[1]
        self._loop = loop
        self._thread = threading.Thread(target=loop.run_forever, name="foxglove-shim", daemon=True)
        self._thread.start()

    async def _relay(self, client: Any) -> None:
        from websockets.asyncio.client import connect
        from websockets.exceptions import ConnectionClosed

        async with connect(self.upstream, subprotocols=[UPSTREAM_SUBPROTOCOL],  # type: ignore[list-item]
                           max_size=None, compression=None, open_timeout=10) as server:

            async def pump(src: Any, dst: Any) -> None:
                with contextlib.suppress(ConnectionClosed):
                    async for frame in src:
                        await dst.send(frame)

            tasks = [asyncio.ensure_future(pump(client, server)), asyncio.ensure_future(pump(server, client))]
            _done, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
            for t in pending:
                t.cancel()

    def stop(self) -> None:
        """Close the listening socket and every relayed connection, then end the loop. Idempotent."""
        loop, self._loop = self._loop, None
        if loop is None:
            return

        async def close() -> None:
            self._server.close()
            await self._server.wait_closed()

        with contextlib.suppress(Exception):
            asyncio.run_coroutine_threadsafe(close(), loop).result(10)
        loop.call_soon_threadsafe(loop.stop)
        if self._thread is not None:
            self._thread.join(10)
            self._thread = None
        loop.close()
