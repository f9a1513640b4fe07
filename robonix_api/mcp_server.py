"""MCP tools for ``@svc.mcp(contract)`` handlers, served over streamable HTTP at ``/mcp/``.

Uses the official ``mcp`` package's low-level server so the input schema can come straight from the
contract's request proto (one source of truth with gRPC); uvicorn runs it in a background thread so
the provider's main thread stays free for signals.
"""

from __future__ import annotations

import json
import logging
import math
import os
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import anyio.to_thread
import mcp_types as types
import uvicorn
from google.protobuf import json_format
from google.protobuf.message import Message
from mcp.server import Server
from mcp.shared.exceptions import MCPError

from robonix_api import auth
from robonix_api.contracts import ContractSpec
from robonix_api.grpc_contracts import MESSAGE_MAX, StatusError, check_strings, invoke
from robonix_api.mcp_tools import MCP_PATH, tool_shape
from robonix_api.netutil import bind_listener
from robonix_api.tool import build_input, wire_output_for_json
from robonix_common.finite_json import non_finite_message

log = logging.getLogger(__name__)

#: A session with no request for this long is closed (its memory released); override with
#: ``ROBONIX_MCP_SESSION_IDLE_S``.
DEFAULT_SESSION_IDLE_S = 300.0
#: At most this many sessions per server; more initialize calls answer HTTP 503 until one closes or
#: idles out. Override with ``ROBONIX_MCP_MAX_SESSIONS``.
DEFAULT_MAX_SESSIONS = 100


def session_limits() -> dict[str, Any]:
    """Keyword arguments for ``streamable_http_app``: idle expiry and a per-server session cap, so a
    flood of ``initialize`` calls cannot grow a server's memory without bound. A bad environment value
    falls back to the default with a warning (a limit must never be switched off by a typo)."""
    idle = env_number("ROBONIX_MCP_SESSION_IDLE_S", DEFAULT_SESSION_IDLE_S, float)
    cap = env_number("ROBONIX_MCP_MAX_SESSIONS", DEFAULT_MAX_SESSIONS, int)
    return {"session_idle_timeout": idle, "max_sessions": cap}


def env_number(name: str, default: Any, kind: type) -> Any:
    """A positive finite number from the environment, else ``default`` (with a warning for a bad value)."""
    raw = os.environ.get(name, "").strip()
    if not raw:
        return default
    try:
        value = kind(raw)
    except ValueError:
        value = None
    if value is None or not math.isfinite(value) or value <= 0:
        log.warning("%s=%r is not a positive number; using %s", name, raw[:40], default)
        return default
    return value


@dataclass
class McpTool:
    """One contract exposed as an MCP tool. The request type is the contract's request proto, or the
    handler's annotated input class when that is a robonix codegen class (``json_schema``/``from_dict``)."""

    spec: ContractSpec
    handler: Callable[..., Any]
    description: str
    request_cls: type
    input_schema: dict[str, Any]

    @property
    def name(self) -> str:
        """The MCP tool name: the contract id's last segment."""
        return self.spec.tool_name

    @classmethod
    def build(cls, spec: ContractSpec, handler: Callable[..., Any], description: str = "") -> McpTool:
        """A tool for ``spec`` served by ``handler``, its input schema derived from the request type."""
        shape = tool_shape(spec, handler, description)
        return cls(spec, handler, shape.description, shape.request_cls, shape.input_schema)

    def call(self, arguments: dict[str, Any]) -> types.CallToolResult:
        """Parse the arguments into the request type, run the handler, return structured output."""
        try:
            request = build_input(self.request_cls, arguments)
        except (json_format.ParseError, TypeError, ValueError, KeyError) as exc:
            return _tool_error(f"invalid arguments for tool {self.name}: {exc}")
        try:
            check_strings(request)
            response = invoke(self.handler, request, None)
        except StatusError as exc:
            return _tool_error(f"{self.name}: {exc}")
        except Exception as exc:  # report to the caller, keep serving
            log.exception("MCP tool %s raised", self.name)
            return _tool_error(f"{self.name}: {type(exc).__name__}: {exc}")
        data = wire_output_for_json(response)
        if not isinstance(data, dict):
            if isinstance(data, Message) or not isinstance(data, (str, int, float, bool, list, type(None))):
                return _tool_error(f"{self.name}: handler returned {type(response).__name__}, expected a proto "
                                   "message or JSON data")
            data = {"result": data}
        return types.CallToolResult(content=[types.TextContent(type="text", text=json.dumps(data))],
                                    structured_content=data)


def token_refusal(ctx: Any, contract_id: str, tool_name: str) -> str | None:
    """With a deployment token set, a tool of a state-changing contract wants it in the HTTP request
    (``Authorization: Bearer <token>``); None when the call may run, else the error text."""
    if auth.is_read_only(contract_id):
        return None
    request = getattr(ctx, "request", None)
    bad = auth.refusal(auth.token_from_headers(getattr(request, "headers", None)), tool_name)
    return bad[1] if bad else None


def _tool_error(text: str) -> types.CallToolResult:
    if len(text) > MESSAGE_MAX:  # never echo unbounded input back
        text = text[: MESSAGE_MAX - 20] + f"... ({len(text)} chars)"
    return types.CallToolResult(content=[types.TextContent(type="text", text=text)], is_error=True)


class McpToolServer:
    """A streamable-HTTP MCP server for a set of tools, on its own thread; ``start()`` gives the port."""

    def __init__(self, name: str, tools: list[McpTool], host: str = "127.0.0.1") -> None:
        self._tools = {t.name: t for t in tools}
        self._host = host
        self._asgi: AsgiServer | None = None
        self.port = 0
        self._mcp = Server(name, on_list_tools=self._list_tools, on_call_tool=self._call_tool,
                           get_tool_input_schema=self._schema_of)

    async def _list_tools(self, ctx: Any, params: Any) -> types.ListToolsResult:
        return types.ListToolsResult(tools=[
            types.Tool(name=t.name, description=t.description, input_schema=t.input_schema)
            for t in self._tools.values()
        ])

    def _schema_of(self, name: str) -> dict[str, Any] | None:
        tool = self._tools.get(name)
        return tool.input_schema if tool else None

    async def _call_tool(self, ctx: Any, params: types.CallToolRequestParams) -> types.CallToolResult:
        tool = self._tools.get(params.name)
        if tool is None:
            raise MCPError(code=types.INVALID_PARAMS, message=f"unknown tool {params.name!r}; "
                           f"known: {sorted(self._tools)}")
        refused = token_refusal(ctx, tool.spec.id, tool.name)
        if refused:
            return _tool_error(refused)
        bad = non_finite_message(dict(params.arguments or {}))
        if bad:
            return _tool_error(f"{tool.name}: {bad}")
        # Handlers are plain blocking functions; keep the event loop free.
        return await anyio.to_thread.run_sync(tool.call, dict(params.arguments or {}))

    def start(self, timeout_s: float = 30.0, sock: socket.socket | None = None) -> int:
        """Serve in a daemon thread (on ``sock`` if given, else on port 0 of the host); return the port
        once accepting."""
        app = self._mcp.streamable_http_app(streamable_http_path=MCP_PATH, host=self._host, **session_limits())
        self._asgi = AsgiServer(app, host=self._host)
        self.port = self._asgi.start(timeout_s, sock=sock)
        return self.port

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop serving and wait up to ``timeout_s`` for the server thread."""
        if self._asgi is not None:
            self._asgi.stop(timeout_s)
            self._asgi = None


class AsgiServer:
    """An ASGI app (an MCP server's streamable-HTTP app) under uvicorn on a daemon thread, port 0."""

    def __init__(self, app: Any, host: str = "127.0.0.1", name: str = "mcp-server") -> None:
        self._app = app
        self._host = host
        self._name = name
        self._server: uvicorn.Server | None = None
        self._thread: threading.Thread | None = None
        self._sock: socket.socket | None = None
        self.port = 0

    def start(self, timeout_s: float = 30.0, sock: socket.socket | None = None) -> int:
        """Serve in a daemon thread, return the port once accepting. ``sock`` is a socket already bound
        (and possibly listening, see :func:`bind_listener`); without it port 0 of the host is bound."""
        sock = sock if sock is not None else bind_listener(self._host, listen=False)
        self.port = sock.getsockname()[1]
        config = uvicorn.Config(self._app, log_level="warning", lifespan="on", timeout_graceful_shutdown=2)
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(target=self._server.run, kwargs={"sockets": [sock]},
                                        name=self._name, daemon=True)
        self._thread.start()
        deadline = time.monotonic() + timeout_s
        while not self._server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                sock.close()
                raise RuntimeError(f"{self._name} on {self._host}:{self.port} did not start")
            time.sleep(0.02)
        self._sock = sock
        return self.port

    def stop(self, timeout_s: float = 5.0) -> None:
        """Ask uvicorn to exit and wait up to ``timeout_s`` for its thread."""
        if self._server is not None:
            self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout_s)
        self._server = self._thread = None
        if self._sock is not None:
            self._sock.close()
            self._sock = None

