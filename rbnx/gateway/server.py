"""The MCP gateway: one MCP endpoint for a whole deployment.

An agent connects once (streamable HTTP on 127.0.0.1, path ``/mcp/``) and sees

* every provider's MCP tools, namespaced by entry (``nav2.navigate``, ``mapping.save_map``): the
  gateway follows the atlas (a poll every ``poll_s``), fetches each provider's ``tools/list`` with the
  official MCP client when the provider appears or re-registers, and forwards ``tools/call`` to it;
* the lifecycle tools of :mod:`rbnx.gateway.control` (``list_services``, ``activate``, ``deactivate``,
  ``configure``, ``cleanup``/``reset``, ``shutdown``), so the agent decides when a service runs.

When the set of tools changes (a provider came, went or re-registered with other tools), clients are
told with ``notifications/tools/list_changed``: on a 2026-07-28 connection through their
``subscriptions/listen`` stream, on an older (handshake) connection on their session's stream.
Every failure is a tool error (``isError``) whose text names the problem; an unknown entry lists the
known ones.
"""

from __future__ import annotations

import json
import logging
import socket
import weakref
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass
from typing import Any

import anyio
import anyio.to_thread
import mcp_types as types
from mcp.server import Server
from mcp.server.lowlevel.server import NotificationOptions
from mcp.server.subscriptions import InMemorySubscriptionBus, ListenHandler, ToolsListChanged
from mcp_types.version import MODERN_PROTOCOL_VERSIONS

from rbnx.atlas_rpc import Atlas, AtlasError
from rbnx.gateway.control import ControlError, LifecycleControl
from rbnx.gateway.quota import DEFAULT_ANON_SESSIONS, SessionQuota
from robonix_api import auth
from robonix_api.mcp_server import AsgiServer, env_number, session_limits
from robonix_api.mcp_tools import MCP_PATH
from robonix_api.proto_gen import atlas_pb2
from robonix_common.finite_json import non_finite_message

log = logging.getLogger("rbnx.gateway")

POLL_S = 1.0
FETCH_TIMEOUT_S = 20.0
CALL_TIMEOUT_S = 120.0
TERMINATED = atlas_pb2.STATE_TERMINATED
READ_ONLY_TOOLS = auth.read_only_tool_names()

_ENTRY = {"entry": {"type": "string", "description": "deploy entry name (see list_services)"}}
LIFECYCLE_TOOLS: dict[str, tuple[str, dict[str, Any], list[str]]] = {
    "list_services": ("The deployment's entries: entry, kind, state (registered/inactive/active/error/"
                      "terminated/absent), detail, autostart, restarts, reinits.", {}, []),
    "activate": ("Start an entry running (INACTIVE -> ACTIVE), e.g. resume SLAM mapping.", _ENTRY, ["entry"]),
    "deactivate": ("Pause an entry (ACTIVE -> INACTIVE). A paused map service still serves its last map; "
                   "paused navigation rejects goals.", _ENTRY, ["entry"]),
    "configure": ("Re-initialize an entry with its config changed by a JSON merge patch (null deletes a key). "
                  "An active entry is paused, re-initialized and resumed. The provider validates the config.",
                  {**_ENTRY, "config": {"type": "object", "description": "merge patch of the entry's config"}},
                  ["entry", "config"]),
    "cleanup": ("Re-initialize an entry with its deploy-file config (patches dropped): a fresh session, "
                "left INACTIVE.", _ENTRY, ["entry"]),
    "reset": ("Same as cleanup.", _ENTRY, ["entry"]),
    "shutdown": ("Shut down one entry (its process exits), or with no entry the whole deployment.",
                 {"entry": {"type": "string", "description": "entry to stop; omit to stop everything"}}, []),
}


@dataclass(frozen=True)
class ProxiedTool:
    """A provider's tool as the gateway lists it (``name`` = ``<entry>.<tool>``)."""

    name: str
    provider: str
    url: str
    tool: types.Tool


def _text_result(text: str, data: Any = None, error: bool = False) -> types.CallToolResult:
    content = [types.TextContent(type="text", text=text)]
    if error:
        return types.CallToolResult(content=content, is_error=True)
    return types.CallToolResult(content=content, structured_content=data)


class _Server(Server[Any]):
    """Advertises ``tools.listChanged`` to handshake-era clients too (the SDK's default says false)."""

    def create_initialization_options(self, notification_options: NotificationOptions | None = None,
                                      *args: Any, **kwargs: Any) -> Any:
        return super().create_initialization_options(notification_options or NotificationOptions(tools_changed=True),
                                                      *args, **kwargs)


class Gateway:
    """The gateway server; :meth:`start` serves it on its own thread and returns the URL."""

    def __init__(self, atlas_addr: str, control: LifecycleControl, *, host: str = "127.0.0.1",
                 poll_s: float = POLL_S, fetch: Callable[[str], Any] | None = None) -> None:
        self.atlas_addr = atlas_addr
        self.control = control
        self.host = host
        self.poll_s = poll_s
        self.url = ""
        self._tools: dict[str, ProxiedTool] = {}
        self._seen: dict[str, tuple[Any, ...]] = {}  # provider -> what its tools were fetched for
        self._by_provider: dict[str, list[ProxiedTool]] = {}
        self._bus = InMemorySubscriptionBus()
        self._listen = ListenHandler(self._bus)
        self._legacy: weakref.WeakSet[Any] = weakref.WeakSet()
        self._fetch = fetch or fetch_tools
        self.changes = 0  # how often the tool set changed (notifications sent)
        self._server = _Server("robonix-gateway", version="1",
                               instructions=("One endpoint for the robot: provider tools as <entry>.<tool>, and "
                                             "lifecycle tools (list_services, activate, deactivate, configure, "
                                             "cleanup/reset, shutdown) to decide which services run."),
                               lifespan=self._lifespan, on_list_tools=self._list_tools, on_call_tool=self._call_tool,
                               on_subscriptions_listen=self._on_listen)
        self._http: AsgiServer | None = None
        self._tg: Any = None  # the lifespan's task group: the watcher and the provider links run in it
        self._links: dict[str, _Link] = {}

    # ------------------------------------------------------------------ serving
    def start(self, timeout_s: float = 30.0, sock: socket.socket | None = None) -> str:
        """Serve (on ``sock`` when given: a socket bound and listening already); returns the URL."""
        limits = session_limits()
        holder_cap = limits["max_sessions"]
        anon_cap = min(holder_cap, env_number("ROBONIX_MCP_MAX_ANON_SESSIONS", DEFAULT_ANON_SESSIONS, int))
        if auth.current_token():  # each identity its own quota; the SDK's cap bounds the sum
            limits["max_sessions"] = holder_cap + anon_cap
        app = self._server.streamable_http_app(streamable_http_path=MCP_PATH, host=self.host, **limits)
        manager = self._server.session_manager
        app = SessionQuota(app, lambda: manager._server_instances,  # the SDK keeps its open sessions there
                           anon_cap=anon_cap, holder_cap=holder_cap)
        self._http = AsgiServer(app, host=self.host, name="mcp-gateway")
        port = self._http.start(timeout_s, sock=sock)
        self.url = f"http://{self.host}:{port}{MCP_PATH}"
        return self.url

    def stop(self, timeout_s: float = 5.0) -> None:
        self._listen.close()  # end listen streams gracefully, so uvicorn's shutdown does not wait on them
        if self._http is not None:
            self._http.stop(timeout_s)
            self._http = None

    @asynccontextmanager
    async def _lifespan(self, _server: Any) -> AsyncIterator[dict[str, Any]]:
        """The atlas watcher runs on the server's own event loop, so notifications need no hand-off."""
        async with anyio.create_task_group() as tg:
            self._tg = tg
            tg.start_soon(self._watch)
            yield {}
            tg.cancel_scope.cancel()
            self._tg = None

    # ------------------------------------------------------------------ following the atlas
    async def _watch(self) -> None:
        while True:
            try:
                await self.refresh()
            except Exception:  # the watcher must outlive any one bad round
                log.exception("gateway refresh failed")
            await anyio.sleep(self.poll_s)

    async def refresh(self) -> bool:
        """One round: re-fetch the tools of providers that changed; notify when the tool set changed."""
        try:
            current = await anyio.to_thread.run_sync(self._mcp_providers)
        except AtlasError as exc:
            log.debug("atlas not reachable: %s", exc)
            return False
        for pid in [p for p in self._by_provider if p not in current]:
            del self._by_provider[pid]
            self._seen.pop(pid, None)
        for pid, (key, contract) in current.items():
            if self._seen.get(pid) == key:
                continue
            fetched = await self._fetch_provider(pid, contract)
            if fetched is not None:
                self._by_provider[pid] = fetched
                self._seen[pid] = key
        tools = {t.name: t for ts in self._by_provider.values() for t in ts}
        urls = {t.url for t in tools.values()}
        for url in [u for u in self._links if u not in urls]:  # a provider left: drop its session
            self._links.pop(url).close()
        changed = set(tools) != set(self._tools) or any(
            tools[n].tool != self._tools[n].tool or tools[n].url != self._tools[n].url for n in tools)
        self._tools = tools
        if changed:
            self.changes += 1
            await self._notify()
        return changed

    def _mcp_providers(self) -> dict[str, tuple[tuple[Any, ...], str]]:
        """provider id -> (what identifies its current registration, one of its MCP contracts)."""
        with Atlas(self.atlas_addr, timeout=5.0) as atlas:
            provs = atlas.query(transport=atlas_pb2.TRANSPORT_MCP)
        out = {}
        for p in provs:
            if p.state == TERMINATED:
                continue
            mcp = sorted(c.contract_id for c in p.capabilities if c.transport == atlas_pb2.TRANSPORT_MCP)
            if mcp:
                out[p.id] = ((getattr(p, "registration_id", ""), tuple(mcp)), mcp[0])
        return out

    async def _fetch_provider(self, pid: str, contract: str) -> list[ProxiedTool] | None:
        try:
            url = await anyio.to_thread.run_sync(self._endpoint, pid, contract)
            with anyio.fail_after(FETCH_TIMEOUT_S):
                listed = await self._fetch(url)
        except Exception as exc:  # not serving yet, or gone again: try on the next round
            log.info("tools of %s not fetched yet: %s", pid, exc)
            return None
        return [ProxiedTool(f"{pid}.{t.name}", pid, url, t) for t in listed]

    def _endpoint(self, pid: str, contract: str) -> str:
        with Atlas(self.atlas_addr, timeout=5.0) as atlas:
            return atlas.endpoint(pid, contract, atlas_pb2.TRANSPORT_MCP)[0]

    async def _notify(self) -> None:
        await self._bus.publish(ToolsListChanged())
        for session in list(self._legacy):
            try:
                await session.send_tool_list_changed()
            except Exception as exc:  # a client that went away
                log.debug("list_changed not delivered: %s", exc)
                self._legacy.discard(session)

    def _remember(self, ctx: Any) -> None:
        """Keep (weakly) the connection of a handshake-era client: its list_changed goes on that connection.

        ``ctx.session`` is a per-request proxy; the SDK exposes the connection behind it only privately,
        and both offer ``send_tool_list_changed``.
        """
        if getattr(ctx, "protocol_version", None) in MODERN_PROTOCOL_VERSIONS or ctx.session is None:
            return
        self._legacy.add(getattr(ctx.session, "_connection", ctx.session))

    async def _on_listen(self, ctx: Any, params: types.SubscriptionsListenRequestParams) -> Any:
        return await self._listen(ctx, params)

    # ------------------------------------------------------------------ MCP handlers
    async def _list_tools(self, ctx: Any, params: Any) -> types.ListToolsResult:
        self._remember(ctx)
        tools = [types.Tool(name=name, description=desc,
                            input_schema={"type": "object", "properties": props, "required": req})
                 for name, (desc, props, req) in LIFECYCLE_TOOLS.items()]
        for t in sorted(self._tools.values(), key=lambda t: t.name):
            tools.append(types.Tool(name=t.name, description=f"[{t.provider}] {t.tool.description or ''}".strip(),
                                    input_schema=t.tool.input_schema, output_schema=t.tool.output_schema))
        return types.ListToolsResult(tools=tools)

    async def _call_tool(self, ctx: Any, params: types.CallToolRequestParams) -> types.CallToolResult:
        self._remember(ctx)
        name, args = params.name, dict(params.arguments or {})
        refused = self._token_refusal(ctx, name)
        if refused:
            return _text_result(refused, error=True)
        bad = non_finite_message(args)
        if bad:  # forwarded on, NaN would arrive as null, i.e. 0
            return _text_result(f"{name}: {bad}", error=True)
        if name in LIFECYCLE_TOOLS:
            return await anyio.to_thread.run_sync(self._lifecycle, name, args)
        tool = self._tools.get(name)
        if tool is None:
            return _text_result(self._unknown(name), error=True)
        try:
            return await self._forward(tool.url, tool.tool.name, args)
        except Exception as exc:  # the provider went away mid-call, or answered garbage
            return _text_result(f"{name}: call to {tool.provider} at {tool.url} failed: {type(exc).__name__}: {exc}",
                                error=True)

    def _token_refusal(self, ctx: Any, name: str) -> str | None:
        """With a deployment token, everything but reading (list_services, read-only provider tools) wants
        the caller's ``Authorization: Bearer``; the gateway forwards with its own token, so it must not
        be an open door to the providers' state-changing tools."""
        if name == "list_services":
            return None
        tool = self._tools.get(name)
        if tool is not None and tool.tool.name in READ_ONLY_TOOLS:
            return None
        if tool is None and name not in LIFECYCLE_TOOLS:
            return None  # unknown: answered as such
        request = getattr(ctx, "request", None)
        bad = auth.refusal(auth.token_from_headers(getattr(request, "headers", None)), name)
        return bad[1] if bad else None

    async def _forward(self, url: str, tool: str, args: dict[str, Any]) -> types.CallToolResult:
        """On the provider's kept-open session; a broken one is replaced once, else a one-off session."""
        for _ in range(2):
            link = self._links.get(url)
            if link is None or link.dead:
                if self._tg is None:
                    break
                link = self._links[url] = _Link(url)
                self._tg.start_soon(link.run)
            client = await link.wait()
            if client is None:
                self._links.pop(url, None)
                continue
            try:
                return await client.call_tool(tool, args)
            except Exception as exc:  # the session broke (provider restarted?): retry on a fresh one
                log.info("session to %s broke (%s); reconnecting", url, exc)
                link.close()
                self._links.pop(url, None)
        return await forward(url, tool, args)

    def _unknown(self, name: str) -> str:
        entry, dot, _ = name.partition(".")
        entries = sorted({t.provider for t in self._tools.values()})
        if not dot:
            return (f"unknown tool {name!r}: provider tools are <entry>.<tool> "
                    f"(entries: {', '.join(entries) or 'none'}); lifecycle tools: {', '.join(LIFECYCLE_TOOLS)}")
        if entry not in entries:
            return f"unknown entry {entry!r} in tool {name!r}; known entries with tools: {', '.join(entries) or 'none'}"
        mine = sorted(t.name for t in self._tools.values() if t.provider == entry)
        return f"unknown tool {name!r}; {entry} offers: {', '.join(mine)}"

    def _lifecycle(self, name: str, args: dict[str, Any]) -> types.CallToolResult:
        c = self.control
        try:
            if name == "list_services":
                services = c.list_services()
                return _text_result(json.dumps(services), {"services": services})
            entry = args.get("entry")
            if name == "shutdown":
                result = c.shutdown(entry if entry else None)
            elif name == "configure":
                if "config" not in args:
                    raise ControlError("config: required (a JSON object merged into the entry's config)")
                result = c.configure(entry, args["config"])
            elif name in ("cleanup", "reset"):
                result = c.reset(entry)
            else:
                result = getattr(c, name)(entry)
        except ControlError as exc:
            return _text_result(f"{name}: {exc}", error=True)
        return _text_result(json.dumps(result), result)


class _Link:
    """A kept-open MCP session to one provider, owned by a task of the gateway (sessions are task-bound)."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.client: Any = None
        self.dead = False
        self._ready = anyio.Event()
        self._closed = anyio.Event()

    async def run(self) -> None:
        try:
            async with auth.mcp_client(self.url, read_timeout_seconds=CALL_TIMEOUT_S) as client:
                self.client = client
                self._ready.set()
                await self._closed.wait()
        except Exception as exc:  # could not connect, or the session ended badly
            log.info("session to %s ended: %s", self.url, exc)
        finally:
            self.dead = True
            self.client = None
            self._ready.set()

    async def wait(self) -> Any:
        with anyio.move_on_after(FETCH_TIMEOUT_S):
            await self._ready.wait()
        return self.client

    def close(self) -> None:
        self.dead = True
        self._closed.set()


async def fetch_tools(url: str) -> list[types.Tool]:
    """A provider's tools, through the official MCP client."""
    async with auth.mcp_client(url, read_timeout_seconds=FETCH_TIMEOUT_S) as client:
        return list((await client.list_tools(cache_mode="refresh")).tools)


async def forward(url: str, tool: str, args: dict[str, Any]) -> types.CallToolResult:
    """One tools/call on a provider, its result (errors included) passed through unchanged."""
    async with auth.mcp_client(url, read_timeout_seconds=CALL_TIMEOUT_S) as client:
        return await client.call_tool(tool, args)
