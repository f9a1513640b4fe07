"""The MCP gateway against a real atlas and a real in-process provider, through the official MCP client:
namespaced tools follow the atlas (with tools/list_changed on both protocol eras), calls are forwarded,
lifecycle verbs drive the provider's Driver, and every error names the problem."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import Any

import mcp_types as types
import pytest
from mcp import Client

from rbnx.gateway import Entry, Gateway, LifecycleControl, merge_patch
from robonix_api import Err, Ok, Service
from robonix_api.proto_gen import navigation_pb2

pytestmark = pytest.mark.integration

NAV = "robonix/service/navigation/navigate"
DEPLOY_CONFIG = {"speed": 1.0, "nested": {"a": 1, "b": 2}}


class Toolbox:
    """A provider with one MCP tool whose INIT rejects a negative speed, as a real provider validates."""

    def __init__(self, atlas: str, pid: str) -> None:
        self.configs: list[dict[str, Any]] = []
        self.svc = Service(pid, "robonix/service/navigation", atlas=atlas)

        def init(cfg: dict[str, Any]) -> Ok | Err:
            if cfg.get("speed", 0) < 0:
                return Err(f"speed: must be >= 0, got {cfg['speed']}")
            self.configs.append(cfg)
            return Ok()

        self.svc.on_init(init)
        self.svc.on_activate(lambda: Ok())
        self.svc.on_deactivate(lambda: Ok())

        @self.svc.mcp(NAV)
        def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
            """Send the robot to a goal."""
            return navigation_pb2.Navigate_Response(accepted=True, run_id="r1",
                                                    detail=f"to x={req.goal.pose.position.x:g}")

        self.svc.run_in_thread()


@pytest.fixture
def gateway(atlas: str) -> Iterator[Gateway]:
    stopped: list[bool] = []
    control = LifecycleControl(atlas, [Entry("toolbox", "service", DEPLOY_CONFIG), Entry("ghost", "service", {})],
                               driver_timeout=30.0, shutdown_all=lambda: stopped.append(True))
    gw = Gateway(atlas, control, poll_s=0.2)
    gw.start()
    gw.stopped = stopped  # type: ignore[attr-defined]
    try:
        yield gw
    finally:
        gw.stop()


def _text(r: types.CallToolResult) -> str:
    return "".join(getattr(c, "text", "") for c in r.content)


def test_merge_patch_is_rfc7386() -> None:
    assert merge_patch({"a": {"b": 1, "c": 2}, "d": 3}, {"a": {"b": None, "e": [1]}, "d": "x"}) == \
        {"a": {"c": 2, "e": [1]}, "d": "x"}


def test_tools_follow_the_atlas_and_lifecycle_verbs(atlas: str, gateway: Gateway) -> None:
    box: list[Toolbox] = []

    async def scenario() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with Client(gateway.url) as c:
            names = {t.name for t in (await c.list_tools()).tools}
            out["before"] = names
            async with c.listen(tools_list_changed=True) as sub:
                box.append(Toolbox(atlas, "toolbox"))      # a provider arrives ...
                await asyncio.wait_for(sub.__anext__(), 60)  # ... and the gateway says so
                out["after"] = {t.name: t for t in (await c.list_tools()).tools}
                r = await c.call_tool("toolbox.navigate", {"goal": {"pose": {"position": {"x": 2.5}}}})
                out["call"] = r
                out["unknown_tool"] = await c.call_tool("toolbox.fly", {})
                out["unknown_entry"] = await c.call_tool("nobody.navigate", {})
                out["bare"] = await c.call_tool("navigate", {})
                out["services0"] = (await c.call_tool("list_services", {})).structured_content
                out["configure"] = await c.call_tool("configure", {"entry": "toolbox",
                                                                   "config": {"nested": {"a": None, "c": 3}}})
                out["activate"] = await c.call_tool("activate", {"entry": "toolbox"})
                out["bad_config"] = await c.call_tool("configure", {"entry": "toolbox", "config": {"speed": -1}})
                out["not_object"] = await c.call_tool("configure", {"entry": "toolbox", "config": 5})
                out["reset"] = await c.call_tool("reset", {"entry": "toolbox"})
                out["unknown_lc"] = await c.call_tool("activate", {"entry": "nope"})
                out["absent"] = await c.call_tool("activate", {"entry": "ghost"})
                out["deactivate"] = await c.call_tool("deactivate", {"entry": "toolbox"})
                box[0].svc.stop()                           # the provider leaves ...
                await asyncio.wait_for(sub.__anext__(), 60)
                out["gone"] = {t.name for t in (await c.list_tools()).tools}
                out["shutdown"] = await c.call_tool("shutdown", {})
        return out

    try:
        out = asyncio.run(asyncio.wait_for(scenario(), 240))
    finally:
        for b in box:
            b.svc.stop()
    lifecycle = {"list_services", "activate", "deactivate", "configure", "cleanup", "reset", "shutdown"}
    assert out["before"] == lifecycle
    assert set(out["after"]) == lifecycle | {"toolbox.navigate"}
    assert out["after"]["toolbox.navigate"].description == "[toolbox] Send the robot to a goal."
    assert out["call"].structured_content == {"accepted": True, "run_id": "r1", "detail": "to x=2.5"}
    assert out["unknown_tool"].is_error
    assert "toolbox offers: toolbox.navigate" in _text(out["unknown_tool"])
    assert out["unknown_entry"].is_error
    assert "unknown entry 'nobody'" in _text(out["unknown_entry"])
    assert "toolbox" in _text(out["unknown_entry"])
    assert out["bare"].is_error
    assert "<entry>.<tool>" in _text(out["bare"])
    svc0 = {s["entry"]: s for s in out["services0"]["services"]}
    assert svc0["toolbox"]["state"] == "registered"
    assert svc0["ghost"]["state"] == "absent"
    assert out["configure"].structured_content["state"] == "inactive", _text(out["configure"])
    assert out["activate"].structured_content["state"] == "active", _text(out["activate"])
    # configure while active: paused, re-INIT with the patch applied, resumed; a rejected config names the field
    assert box[0].configs[0] == {"speed": 1.0, "nested": {"b": 2, "c": 3}}
    assert out["bad_config"].is_error
    assert "speed: must be >= 0" in _text(out["bad_config"])
    assert out["not_object"].is_error
    assert "config: must be a JSON object" in _text(out["not_object"])
    assert out["reset"].structured_content["state"] == "inactive", _text(out["reset"])
    assert box[0].configs[-1] == DEPLOY_CONFIG
    assert out["unknown_lc"].is_error
    assert "unknown entry 'nope'; known: toolbox, ghost" in _text(out["unknown_lc"])
    assert out["absent"].is_error
    assert "ghost: not registered" in _text(out["absent"])
    assert out["deactivate"].structured_content["state"] == "inactive"
    assert out["gone"] == lifecycle
    assert not out["shutdown"].is_error
    assert gateway.stopped == [True]


def test_handshake_era_client_gets_list_changed(atlas: str, gateway: Gateway) -> None:
    seen: list[Any] = []
    box: list[Toolbox] = []

    async def on_message(msg: Any) -> None:
        if isinstance(msg, types.ToolListChangedNotification):
            seen.append(msg)

    async def scenario() -> set[str]:
        async with Client(gateway.url, mode="legacy", message_handler=on_message) as c:
            assert c.server_capabilities.tools is not None
            assert c.server_capabilities.tools.list_changed
            await c.list_tools()
            box.append(Toolbox(atlas, "toolbox2"))
            for _ in range(600):
                if seen:
                    break
                await asyncio.sleep(0.1)
            return {t.name for t in (await c.list_tools()).tools}

    try:
        names = asyncio.run(asyncio.wait_for(scenario(), 120))
    finally:
        for b in box:
            b.svc.stop()
    assert seen, "no notifications/tools/list_changed on the handshake-era session"
    assert "toolbox2.navigate" in names
