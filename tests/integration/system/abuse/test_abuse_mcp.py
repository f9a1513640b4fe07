"""Property-based abuse of every MCP tool the deployment's providers serve: hypothesis draws arguments
from each tool's input schema (hostile values, wrong types, unknown keys). Every reply must be a tool
result (structured) or a clear tool/protocol error of bounded size; the servers keep serving."""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Iterator
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robonix_api import auth

from .deployment import Deployment
from .strategies import fuzz_settings, schema_value

pytestmark = pytest.mark.integration
EXAMPLES = fuzz_settings(25)


class McpActor:
    """One MCP client session held open by a task on a background event loop; ``call`` is synchronous
    (hypothesis drives examples from this thread, the session lives in its own task)."""

    def __init__(self, url: str, with_token: bool) -> None:
        self.with_token = with_token
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, name="mcp-actor", daemon=True)
        self._thread.start()
        self._inbox: asyncio.Queue[Any] | None = None
        ready: concurrent.futures.Future[Any] = concurrent.futures.Future()
        self._done = asyncio.run_coroutine_threadsafe(self._serve(url, ready), self.loop)
        self.tools = ready.result(120)

    async def _serve(self, url: str, ready: concurrent.futures.Future[Any]) -> None:
        from mcp import Client
        from mcp.shared.exceptions import MCPError

        self._inbox = asyncio.Queue()
        try:
            async with (auth.mcp_client(url) if self.with_token else Client(url)) as client:
                ready.set_result((await client.list_tools()).tools)
                while (item := await self._inbox.get()) is not None:
                    name, args, fut = item
                    try:
                        fut.set_result(("result", await client.call_tool(name, args)))
                    except MCPError as exc:
                        fut.set_result(("protocol error", exc))
                    except Exception as exc:
                        fut.set_result(("broken", exc))
        except BaseException as exc:
            if not ready.done():
                ready.set_exception(exc)
            raise

    def call(self, name: str, args: dict[str, Any]) -> tuple[str, Any]:
        fut: concurrent.futures.Future[tuple[str, Any]] = concurrent.futures.Future()
        assert self._inbox is not None
        self.loop.call_soon_threadsafe(self._inbox.put_nowait, (name, args, fut))
        return fut.result(120)

    def close(self) -> None:
        if self._inbox is not None:
            self.loop.call_soon_threadsafe(self._inbox.put_nowait, None)
        try:
            self._done.result(30)
        finally:
            self.loop.call_soon_threadsafe(self.loop.stop)
            self._thread.join(10)
            self.loop.close()


@pytest.fixture(scope="module")
def actors(deployment: Deployment) -> Iterator[dict[str, tuple[McpActor, McpActor]]]:
    """Per provider: a session holding the deployment's token, and one without."""
    assert auth.current_token(), "the deployment's token was not adopted"
    urls: dict[str, str] = {}
    for provider, contract in deployment.capabilities("mcp"):
        urls.setdefault(provider, deployment.endpoint(provider, contract, "mcp"))
    assert set(urls) == set(deployment.pids), urls
    out = {provider: (McpActor(url, True), McpActor(url, False)) for provider, url in urls.items()}
    try:
        yield out
    finally:
        for pair in out.values():
            for actor in pair:
                actor.close()


def check_reply(kind: str, value: Any, what: str) -> None:
    assert kind != "broken", f"{what}: {type(value).__name__}: {str(value)[:500]}"
    if kind == "protocol error":
        assert 0 < len(str(value)) <= 1200, f"{what}: protocol error of {len(str(value))} chars"
        return
    texts = [getattr(c, "text", "") for c in value.content]
    if value.is_error:
        assert texts, f"{what}: error text {texts[:1]!r:.300}"
        assert texts[0], f"{what}: error text {texts[:1]!r:.300}"
        assert len(texts[0]) <= 1024, f"{what}: error text {texts[:1]!r:.300}"
    else:
        assert isinstance(value.structured_content, dict), f"{what}: no structured result: {texts[:1]!r:.300}"


def fuzz_tool(dep: Deployment, pair: tuple[McpActor, McpActor], label: str, name: str,
              schema: dict[str, Any]) -> None:
    @EXAMPLES
    @given(args=schema_value({**schema, "type": "object"}).filter(lambda a: isinstance(a, dict)),
           actor=st.sampled_from([pair[0], pair[0], pair[0], pair[1]]))
    def run(args: dict[str, Any], actor: McpActor) -> None:
        dep.count(f"MCP {label}")
        kind, value = actor.call(name, args)
        check_reply(kind, value, label)

    run()


def test_every_tool_argument(deployment: Deployment, actors: dict[str, tuple[McpActor, McpActor]]) -> None:
    n_tools = 0
    for provider, pair in sorted(actors.items()):
        for tool in pair[0].tools:
            n_tools += 1
            schema = tool.input_schema if isinstance(tool.input_schema, dict) else {}
            fuzz_tool(deployment, pair, f"{provider}/{tool.name}", tool.name, schema)
            deployment.assert_alive()
    assert n_tools >= 20
