"""The dashboard's web server: one page, a WebSocket of state snapshots, the map PNG, three actions.

Routes: ``/`` the page (package data in ``static/``), ``/ws`` pushes a JSON snapshot whenever the state
changed (at most every ``MIN_PUSH_S``) and at least every ``MAX_PUSH_S`` (≥ 5 Hz), ``/api/map.png`` the current
map image (the page fetches it only when the map's version changed), ``POST /api/goal`` ``{x, y, yaw}``,
``POST /api/cancel``, ``POST /api/lifecycle`` ``{provider, command}``. Binds 127.0.0.1 by default;
who may use it (Host/Origin allow-lists, JSON only, the access key of the printed URL): :mod:`rbnx.dashboard.guard`.
"""

from __future__ import annotations

import asyncio
import json
import socket
import threading
from importlib import resources
from typing import Any

import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect

from rbnx.dashboard.guard import Guard, new_key
from rbnx.dashboard.state import DashboardError, LiveState
from robonix_api.netutil import host_port
from robonix_common.finite_json import non_finite_message

MIN_PUSH_S = 0.04
MAX_PUSH_S = 0.2  # >= 5 updates/s also when nothing moves (the page shows it is live)
STATIC = {"/": ("index.html", "text/html; charset=utf-8"),
          "/app.js": ("app.js", "text/javascript; charset=utf-8"),
          "/style.css": ("style.css", "text/css; charset=utf-8")}


def _static(name: str) -> bytes:
    return resources.files("rbnx.dashboard").joinpath("static", name).read_bytes()


async def _body(request: Request) -> dict[str, Any]:
    """The request's JSON object, or DashboardError (answered 400)."""
    try:
        body = await request.json()
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise DashboardError("body: must be a JSON object") from None
    if not isinstance(body, dict):
        raise DashboardError("body: must be a JSON object")
    bad = non_finite_message(body)
    if bad:
        raise DashboardError(bad)
    return body


def _refused(why: tuple[int, str]) -> Response:
    return JSONResponse({"error": why[1]}, status_code=why[0])


def _action(guard: Guard, fn: Any) -> Any:
    """A POST handler (Host/Origin, JSON content type and the access key checked) that runs ``fn(body)``
    off the event loop and answers its result as JSON."""
    async def handler(request: Request) -> Response:
        refused = await guard.refusal(request, post=True)
        if refused:
            return _refused(refused)
        try:
            body = await _body(request)
            result = await asyncio.to_thread(fn, body)
        except DashboardError as exc:
            return JSONResponse({"error": str(exc)}, status_code=400)
        return JSONResponse(result)
    return handler


def _page(guard: Guard, pages: dict[str, tuple[bytes, str]]) -> Any:
    """The page code (Host/Origin checked); ``/`` also wants the key, and ``/?token=KEY`` (the printed URL)
    hands the key over as a cookie and redirects to ``/``."""
    async def page(request: Request) -> Response:
        refused = await guard.host_refusal(request)
        if refused:
            return _refused(refused)
        if request.url.path == "/":
            token = request.query_params.get("token")
            if token is not None:  # the printed URL: hand the key over as a cookie, drop it from the address
                if not guard.authorized_key(token):
                    return _refused((403, "wrong dashboard access key: open the URL `rbnx dashboard` printed"))
                return Response(status_code=303, headers={"Location": "/", "Set-Cookie": guard.cookie_header(),
                                                          "Cache-Control": "no-store"})
            if not guard.authorized(request):
                return _refused((401, "dashboard access key required: open the URL printed by `rbnx dashboard` "
                                      "(.../?token=...)"))
        body, mime = pages[request.url.path]
        return Response(body, media_type=mime, headers={"Cache-Control": "no-store"})

    return page


def build_app(state: LiveState, guard: Guard) -> Starlette:
    pages = {path: (_static(name), mime) for path, (name, mime) in STATIC.items()}

    page = _page(guard, pages)

    async def map_png(request: Request) -> Response:
        refused = await guard.refusal(request)
        if refused:
            return _refused(refused)
        img = state.map_image()
        if img is None:
            return JSONResponse({"error": "no map yet"}, status_code=404)
        return Response(img.png, media_type="image/png",
                        headers={"Cache-Control": "no-store", "X-Map-Version": str(img.version)})

    def goal(body: dict[str, Any]) -> dict[str, Any]:
        missing = [k for k in ("x", "y") if k not in body]
        if missing:
            raise DashboardError(f"{missing[0]}: required")
        return state.send_goal(body["x"], body["y"], body.get("yaw", 0.0))

    def lifecycle(body: dict[str, Any]) -> dict[str, Any]:
        provider = body.get("provider")
        if not isinstance(provider, str) or not provider:
            raise DashboardError("provider: required (a provider id)")
        return state.lifecycle(provider, str(body.get("command", "")))

    async def ws(socket: WebSocket) -> None:
        if await guard.refusal(socket):  # foreign Origin/Host or no key: no handshake, no live map
            await socket.close(code=1008)
            return
        await socket.accept()
        seen = -1
        try:
            while True:
                # on every change (at most every MIN_PUSH_S), and at least every MAX_PUSH_S regardless
                seen = await asyncio.to_thread(state.wait_change, seen, MAX_PUSH_S)
                await socket.send_text(json.dumps(state.snapshot(), separators=(",", ":")))
                await asyncio.sleep(MIN_PUSH_S)
        except (WebSocketDisconnect, RuntimeError):
            return

    routes = [Route(p, page) for p in STATIC] + [
        Route("/api/map.png", map_png),
        Route("/api/goal", _action(guard, goal), methods=["POST"]),
        Route("/api/cancel", _action(guard, lambda _b: state.cancel()), methods=["POST"]),
        Route("/api/lifecycle", _action(guard, lifecycle), methods=["POST"]),
        WebSocketRoute("/ws", ws),
    ]
    return Starlette(routes=routes)


class DashboardServer:
    """LiveState + uvicorn; ``start()`` serves from a background thread (for boot/demo --dashboard),
    `rbnx dashboard` waits on ``running()``."""

    def __init__(self, state: LiveState, host: str = "127.0.0.1", port: int = 8765, key: str | None = None) -> None:
        self.state = state
        self.host = host
        self.key = key or new_key()
        self._sock = _listen(host, port)  # bound now: the allow-lists carry the real port
        self.port = self._sock.getsockname()[1]
        self.guard = Guard(host, self.port, self.key)
        config = uvicorn.Config(build_app(state, self.guard), host=host, port=self.port, log_level="warning",
                                ws="websockets-sansio", lifespan="off")
        self.server = uvicorn.Server(config)
        self._thread: threading.Thread | None = None

    @property
    def base_url(self) -> str:
        """``http://HOST:PORT/`` (without the key)."""
        return f"http://{host_port(self.host, self.port)}/"

    @property
    def url(self) -> str:
        """The URL to open: it carries the access key once, the page then holds it in a cookie."""
        return f"{self.base_url}?token={self.key}"

    def start(self, timeout: float = 10.0) -> str:
        self.state.start()
        self._thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self._sock]},
                                        name="dashboard-http", daemon=True)
        self._thread.start()
        ev = threading.Event()
        while not self.server.started and self._thread.is_alive():
            ev.wait(0.02)
            timeout -= 0.02
            if timeout <= 0:
                break
        if not self.server.started:
            self.stop()
            raise OSError(f"dashboard could not listen on {self.server.config.host}:{self.server.config.port}")
        return self.url

    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def stop(self) -> None:
        self.server.should_exit = True
        if self._thread is not None:
            self._thread.join(10.0)
        self._sock.close()
        self.state.close()


def _listen(host: str, port: int) -> socket.socket:
    """A TCP socket bound to ``host:port`` (OSError naming them when taken)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        raise OSError(f"dashboard could not listen on {host}:{port}: {exc.strerror or exc}") from None
    return sock
