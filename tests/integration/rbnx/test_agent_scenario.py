"""Acceptance: an agent in charge of a real deployment, through nothing but the official MCP client.

``rbnx boot`` runs the MuJoCo base, SLAM (``autostart: false``) and navigation with an MCP gateway and
OpenTelemetry pointed at a real OTLP/HTTP receiver in this test. The agent lists tools, decides when
SLAM runs (activate; navigation comes up once there is a map), drives two goals, pauses SLAM (the map
stops changing yet is still served and navigation on it still works), resumes it, saves the map and
shuts the whole deployment down through the gateway; no process is left. The receiver gets the
Navigate span in the trace of a gRPC client that sent W3C trace context, and ``slam.occupancy_grid``
spans whose inline PNG decodes to the map's size. Everything waits for states, never for time.
"""

from __future__ import annotations

import asyncio
import base64
import gzip
import io
import json
import os
import re
import secrets
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
import yaml
from mcp import Client
from opentelemetry.proto.collector.trace.v1.trace_service_pb2 import (
    ExportTraceServiceRequest,
    ExportTraceServiceResponse,
)
from PIL import Image
from support.boot import RbnxBoot, rbnx_cmd
from support.procs import REPO, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.auth import channel as token_channel
from robonix_api.auth import mcp_client
from robonix_api.dds import DdsNode, MapLifecycle
from robonix_api.proto_gen import navigation_pb2 as nav_pb
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc

pytestmark = pytest.mark.integration

ROOM: dict[str, Any] = {
    "name": "agent_room", "bounds": [0, 0, 6, 5],
    "walls": [{"start": a, "end": b, "thickness": 0.1, "height": 2.0}
              for a, b in (([0, 0], [6, 0]), ([6, 0], [6, 5]), ([6, 5], [0, 5]), ([0, 5], [0, 0]))],
    "boxes": [{"name": "crate", "center": [4.2, 1.2], "size": [0.6, 0.8], "height": 0.8},
              {"name": "shelf", "center": [1.0, 3.9], "size": [1.2, 0.4], "height": 1.5}],
    "start": {"x": 1.5, "y": 1.5, "yaw": 0.0},
}
GOALS = [(4.8, 3.4), (2.2, 2.6)]
HOME = (1.5, 1.5)
DEADLINE_S = 400.0


# ---------------------------------------------------------------- a real OTLP/HTTP receiver


class OtlpReceiver:
    """POST /v1/traces with ExportTraceServiceRequest protobufs; keeps every span as a plain dict."""

    def __init__(self) -> None:
        self.spans: list[dict[str, Any]] = []
        self.lock = threading.Lock()
        receiver = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:
                body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
                if self.headers.get("Content-Encoding") == "gzip":
                    body = gzip.decompress(body)
                req = ExportTraceServiceRequest.FromString(body)
                receiver.add(req)
                out = ExportTraceServiceResponse().SerializeToString()
                self.send_response(200)
                self.send_header("Content-Type", "application/x-protobuf")
                self.send_header("Content-Length", str(len(out)))
                self.end_headers()
                self.wfile.write(out)

            def log_message(self, *_: Any) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}"
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def add(self, req: ExportTraceServiceRequest) -> None:
        for rs in req.resource_spans:
            service = next((a.value.string_value for a in rs.resource.attributes if a.key == "service.name"), "")
            for ss in rs.scope_spans:
                for s in ss.spans:
                    with self.lock:
                        self.spans.append({"name": s.name, "service": service, "trace_id": s.trace_id.hex(),
                                           "parent": s.parent_span_id.hex(), "status": s.status.code,
                                           "attrs": {a.key: _value(a.value) for a in s.attributes}})

    def find(self, name: str, **match: Any) -> list[dict[str, Any]]:
        with self.lock:
            return [s for s in self.spans if s["name"] == name and all(s.get(k) == v for k, v in match.items())]

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


def _value(v: Any) -> Any:
    kind = v.WhichOneof("value")
    if kind == "array_value":
        return [_value(x) for x in v.array_value.values]
    return getattr(v, kind) if kind else None


# ---------------------------------------------------------------- the deployment


class Deployment:
    def __init__(self, boot: RbnxBoot, receiver: OtlpReceiver, map_dir: Path) -> None:
        self.boot, self.receiver, self.map_dir = boot, receiver, map_dir
        m = wait_until(lambda: re.search(r"MCP gateway: (\S+)", boot.output()), 120, "the gateway URL", 0.2)
        self.url = m.group(1)
        self.state = boot.state()
        assert self.state["gateway"] == self.url
        boot.adopt_token()  # the agent holds the deployment token (`rbnx token`), as the README says


@pytest.fixture(scope="module")
def deployment(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Deployment]:
    if shutil.which("bash") is None:
        pytest.skip("rbnx runs start: with bash")
    tmp = tmp_path_factory.mktemp("agent")
    receiver = OtlpReceiver()
    deploy = {
        "manifestVersion": 1, "name": "agent_in_charge",
        "env": {"ROBONIX_HEARTBEAT_PERIOD_S": "2", "ROBONIX_NAV2_FORCE": "native",
                "OTEL_EXPORTER_OTLP_ENDPOINT": receiver.url, "OTEL_BSP_SCHEDULE_DELAY": "200"},
        "system": {"atlas": {"listen": "${RBNX_ATLAS_LISTEN:-127.0.0.1:0}"}},
        "primitive": [{"name": "panda_mobile", "path": str(REPO / "hal_panda_mobile"),
                       "config": {"scene": ROOM, "real_time_factor": 2.0, "odom_noise": "none", "use_sim_time": True,
                                  "lidar_noise": {"noise_std": 0.0, "dropout_prob": 0.0}}}],
        "service": [
            {"name": "mapping", "path": str(REPO / "slam_service"), "autostart": False,
             "config": {"mode": "mapping", "use_sim_time": True, "map_dir": str(tmp / "maps"),
                        "map_publish_period_s": 0.5}},
            {"name": "nav2", "path": str(REPO),
             "config": {"params_profile": "sim", "use_sim_time": True, "action_wait_s": 300}},
        ],
    }
    path = tmp / "deploy.yaml"
    path.write_text(yaml.safe_dump(deploy, sort_keys=False))
    with RbnxBoot(path, tmp) as boot:
        try:
            _CURRENT[:] = [Deployment(boot, receiver, tmp / "maps")]
            yield _CURRENT[0]
        finally:
            _CURRENT.clear()
            if boot.proc.poll() is None:  # a failed test left it running: Ctrl-C it, as a person would
                boot.interrupt()
            if boot.pids:
                boot.wait_all_exited(60)
            receiver.close()
    for name in ("mapping", "nav2", "panda_mobile"):
        log = boot.log(name)
        assert "Traceback" not in log, log[-3000:]


# ---------------------------------------------------------------- the agent's helpers

_CURRENT: list[Deployment] = []


def _diagnostics() -> str:
    """The tails of rbnx boot's output and of every entry's log, for a failure message."""
    if not _CURRENT:
        return ""
    boot = _CURRENT[0].boot
    parts = [f"--- rbnx boot ---\n{boot.output()[-1500:]}"]
    for log in sorted(boot.logs.glob("*.log")):
        parts.append(f"--- {log.name} ---\n{log.read_text(errors='replace')[-1500:]}")
    return "\n".join(parts)



async def call(c: Client, tool: str, args: dict[str, Any] | None = None) -> Any:
    r = await c.call_tool(tool, args or {})
    text = "".join(getattr(x, "text", "") for x in r.content)
    assert not r.is_error, f"{tool}: {text}\n{_diagnostics()}"
    return r.structured_content if r.structured_content is not None else json.loads(text)


async def poll(c: Client, what: str, fn: Any, timeout_s: float = DEADLINE_S) -> Any:
    """Await ``fn()`` until it returns something truthy (the agent polls; no fixed sleeps)."""
    deadline = time.monotonic() + timeout_s
    last: Any = None
    while time.monotonic() < deadline:
        last = await fn()
        if last:
            return last
        await asyncio.sleep(0.3)
    raise AssertionError(f"timed out waiting for {what}; last {last!r}\n{_diagnostics()}")


async def services(c: Client) -> dict[str, dict[str, Any]]:
    return {s["entry"]: s for s in (await call(c, "list_services"))["services"]}


async def tool_names(c: Client) -> set[str]:
    return {t.name for t in (await c.list_tools()).tools}


async def drive(c: Client, x: float, y: float) -> dict[str, Any]:
    goal = {"goal": {"header": {"frame_id": "map"}, "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1}}}}
    r = await call(c, "nav2.navigate", goal)
    assert r["accepted"], r

    async def done() -> Any:
        st = await call(c, "nav2.status", {"run_id": r["run_id"]})
        return st if st["terminal"] else None

    return await poll(c, f"goal ({x}, {y}) to end", done)


async def slam_stats(c: Client) -> dict[str, Any]:
    r = await call(c, "mapping.get_mode")
    return json.loads(r["detail"])


# ---------------------------------------------------------------- tests (in order: the last shuts down)


@pytest.mark.timeout(1800)
def test_agent_runs_the_robot_through_the_gateway(deployment: Deployment) -> None:
    async def agent() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with mcp_client(deployment.url, read_timeout_seconds=120) as c:
            out["tools0"] = await tool_names(c)
            await poll(c, "mapping INACTIVE", lambda: _state_is(c, "mapping", "inactive"))
            out["booted"] = await services(c)
            out["activate"] = await call(c, "activate", {"entry": "mapping"})
            await poll(c, "every entry ACTIVE", lambda: _all_active(c))
            names = await poll(c, "provider tools", lambda: _has_tools(c, {"nav2.navigate", "mapping.save_map"}))
            out["tools"] = names
            out["goals"] = [await drive(c, *g) for g in GOALS]
            out["deactivate"] = await call(c, "deactivate", {"entry": "mapping"})
            paused = await slam_stats(c)
            out["home"] = await drive(c, *HOME)          # navigation on the paused map still works
            out["paused_stats"] = (paused, await slam_stats(c))
            out["card"] = await call(c, "mapping.map_card")  # the map is still served
            out["reactivate"] = await call(c, "activate", {"entry": "mapping"})
            integrated = paused["engine"]["scans_integrated"]
            await poll(c, "SLAM integrating again",
                       lambda: _integrated_more(c, integrated))
            out["save"] = await call(c, "mapping.save_map", {"map_id": "agent_map", "note": "saved by the agent"})
        return out

    out = asyncio.run(asyncio.wait_for(agent(), 3 * DEADLINE_S))
    assert {"list_services", "activate", "deactivate", "configure", "reset", "shutdown"} <= out["tools0"]
    booted = out["booted"]["mapping"]
    assert booted["state"] == "inactive"
    assert booted["autostart"] is False
    assert out["activate"]["state"] == "active"
    assert {"nav2.navigate", "nav2.status", "nav2.cancel", "mapping.save_map", "mapping.map_card",
            "mapping.get_mode"} <= out["tools"]
    for st in out["goals"]:
        assert st["state"] == "SUCCEEDED", st
    assert out["deactivate"]["state"] == "inactive"
    assert out["home"]["state"] == "SUCCEEDED", out["home"]
    before, after = out["paused_stats"]
    assert before["integrating"] is False
    assert after["integrating"] is False
    # paused: scans still arrive, none is integrated and no new map is published
    assert after["engine"]["scans_integrated"] == before["engine"]["scans_integrated"]
    assert after.get("maps_published", 0) == before.get("maps_published", 0)
    assert after["scans_paused"] > before["scans_paused"]
    card = out["card"]
    assert card["ok"]
    assert card["width"] > 0
    assert card["height"] > 0
    assert out["reactivate"]["state"] == "active"
    assert out["save"]["ok"], out["save"]
    assert (deployment.map_dir / "agent_map" / "map.yaml").is_file()


@pytest.mark.timeout(900)
def test_telemetry_reaches_a_collector(deployment: Deployment) -> None:
    rx = deployment.receiver
    trace_id, parent = secrets.token_hex(16), secrets.token_hex(8)
    with AtlasClient(deployment.state["atlas"]) as atlas:
        nav_cid = "robonix/service/navigation/navigate"
        with atlas.connect_capability(consumer_id="otel_test", provider_id="nav2", contract_id=nav_cid,
                                      transport="grpc") as ch:
            endpoint = ch.endpoint
        with atlas.connect_capability(consumer_id="otel_test", provider_id="nav2",
                                      contract_id=nav_cid + "/status", transport="grpc") as ch:
            status_ep = ch.endpoint
    with token_channel(endpoint) as chan, token_channel(status_ep) as schan:
        req = nav_pb.Navigate_Request()
        req.goal.header.frame_id = "map"
        req.goal.pose.position.x, req.goal.pose.position.y = GOALS[0]
        req.goal.pose.orientation.w = 1.0
        reply = rpc.RobonixServiceNavigationNavigateStub(chan).Navigate(
            req, timeout=60, metadata=[("traceparent", f"00-{trace_id}-{parent}-01")])
        assert reply.accepted, reply.detail
        status = rpc.RobonixServiceNavigationNavigateStatusStub(schan)
        wait_until(lambda: status.GetNavigationStatus(nav_pb.GetNavigationStatus_Request(run_id=reply.run_id),
                                                      timeout=60).state in ("SUCCEEDED", "FAILED", "CANCELED"),
                   DEADLINE_S, "the traced goal to end", 0.3)
    (span,) = wait_until(lambda: rx.find("nav.navigate", trace_id=trace_id), 120, "the Navigate span", 0.2)
    assert span["parent"] == parent
    assert span["service"] == "nav2"
    a = span["attrs"]
    assert a["nav.run_id"] == reply.run_id, a
    assert a["nav.end_state"] == "SUCCEEDED", a
    assert a["nav.goal.x"] == pytest.approx(GOALS[0][0])
    assert a["nav.distance_driven_m"] > 0.5
    assert a["nav.recoveries"] >= 0
    assert a["nav.final_error_m"] < 0.5

    # an agent's own trace over MCP, through the gateway: the MCP SDKs carry it in _meta.traceparent
    from opentelemetry.sdk.trace import TracerProvider

    agent_tracer = TracerProvider().get_tracer("agent")

    async def agent() -> tuple[str, dict[str, Any]]:
        async with mcp_client(deployment.url, read_timeout_seconds=120) as c:
            with agent_tracer.start_as_current_span("agent.task") as task:
                st = await drive(c, *GOALS[1])
                await call(c, "deactivate", {"entry": "mapping"})
                await call(c, "activate", {"entry": "mapping"})
            return format(task.get_span_context().trace_id, "032x"), st

    agent_trace, st = asyncio.run(asyncio.wait_for(agent(), DEADLINE_S))
    assert st["state"] == "SUCCEEDED", st
    (span,) = wait_until(lambda: rx.find("nav.navigate", trace_id=agent_trace), 120, "the MCP goal's span", 0.2)
    assert span["attrs"]["nav.run_id"] == st["run_id"]
    # ... and so do the lifecycle transitions the agent asks the gateway for
    for verb in ("deactivate", "activate"):
        wait_until(lambda v=verb: rx.find(f"lifecycle.{v}", trace_id=agent_trace, service="mapping"), 120,
                   f"lifecycle.{verb} in the agent's trace", 0.2)

    grids = wait_until(lambda: rx.find("slam.occupancy_grid"), 120, "a slam.occupancy_grid span", 0.2)
    g = grids[-1]["attrs"]
    img = Image.open(io.BytesIO(base64.b64decode(g["png_b64"])))
    assert img.size == (g["width"], g["height"])
    assert g["width"] > 20
    assert g["height"] > 20
    assert g["frame_id"] == "map"
    assert g["base_frame"] == "base_link"
    assert g["resolution"] > 0
    assert len(g["footprint_polygon_xy"]) >= 6
    assert len(g["footprint_polygon_xy"]) % 2 == 0
    assert {"robot_x", "robot_y", "robot_yaw", "origin_x", "origin_y"} <= set(g)
    # the agent's lifecycle transitions are spans too (on the provider that made them)
    assert rx.find("lifecycle.activate", service="mapping")
    assert rx.find("lifecycle.deactivate", service="mapping")


@pytest.mark.timeout(300)
def test_slam_publishes_its_lifecycle(deployment: Deployment) -> None:
    """robonix/service/map/lifecycle is declared and latched: a late subscriber sees the latest state."""
    with AtlasClient(deployment.state["atlas"]) as atlas, atlas.connect_capability(
            consumer_id="lifecycle_test", provider_id="mapping", contract_id="robonix/service/map/lifecycle",
            transport="ros2") as ch:
        topic = ch.endpoint
    with DdsNode(name="map_lifecycle_test") as node:
        msg = node.wait_for_message(topic, MapLifecycle, 60, "transient_local")
    assert msg is not None, f"nothing latched on {topic}"
    # INIT (paused), activate, deactivate (paused), activate: the agent's decisions, in order
    assert msg.mode == "mapping", msg
    assert msg.generation >= 4, msg
    assert msg.map_id == "", msg


def rbnx(deployment: Deployment, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, RBNX_STATE_DIR=str(deployment.boot.state_dir))
    return subprocess.run([*rbnx_cmd(), "--atlas", deployment.state["atlas"], *args], env=env, text=True,
                          capture_output=True, timeout=600)


@pytest.mark.slow  # dozens of rbnx CLI runs against the deployment: the slow suite of .ci/run
@pytest.mark.timeout(900)
def test_a_person_at_a_terminal(deployment: Deployment) -> None:
    deploy = deployment.state["deploy"]
    tools = rbnx(deployment, "tools")
    assert tools.returncode == 0, tools.stdout + tools.stderr
    assert deployment.url in tools.stdout, tools.stdout + tools.stderr
    # mapping is `autostart: false`: run alone (the slow suite), nobody has activated it yet
    if not re.search(r"^mapping\s+service\s+active", rbnx(deployment, "lifecycle", "-f", deploy).stdout, re.M):
        r = rbnx(deployment, "lifecycle", "-f", deploy, "mapping", "activate")
        assert (r.returncode, r.stdout.strip()) == (0, "mapping: active"), r.stdout + r.stderr
    # nav2 comes up once mapping serves /map (it answers Deferred until then)
    wait_until(lambda: re.search(r"^nav2\s+service\s+active", rbnx(deployment, "lifecycle", "-f", deploy).stdout,
                                 re.M), 300, "nav2 ACTIVE", 2.0)
    listed = rbnx(deployment, "lifecycle", "-f", deploy)
    assert listed.returncode == 0, listed.stderr
    assert re.search(r"^mapping\s+service\s+active", listed.stdout, re.M), listed.stdout
    assert re.search(r"^nav2\s+service\s+active", listed.stdout, re.M), listed.stdout

    r = rbnx(deployment, "lifecycle", "-f", deploy, "mapping", "deactivate")
    assert (r.returncode, r.stdout.strip()) == (0, "mapping: inactive"), r.stderr
    r = rbnx(deployment, "lifecycle", "-f", deploy, "mapping", "configure", "-s", "map_publish_period_s=-1")
    assert r.returncode == 1, r.stdout + r.stderr
    assert "map_publish_period_s" in r.stderr, r.stdout + r.stderr  # the provider's reason
    r = rbnx(deployment, "lifecycle", "-f", deploy, "mapping", "configure", "-s", "map_publish_period_s=0.7")
    assert (r.returncode, r.stdout.strip()) == (0, "mapping: inactive"), r.stderr
    r = rbnx(deployment, "lifecycle", "-f", deploy, "mapping", "activate")
    assert (r.returncode, r.stdout.strip()) == (0, "mapping: active"), r.stderr

    r = rbnx(deployment, "lifecycle", "-f", deploy, "nosuch", "activate")
    assert r.returncode == 1, r.stderr
    assert "unknown entry 'nosuch'; known: panda_mobile, mapping, nav2" in r.stderr, r.stderr
    r = rbnx(deployment, "lifecycle", "-f", deploy, "mapping", "configure")
    assert r.returncode == 2
    assert "-s KEY=VALUE or --patch" in r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.timeout(600)
def test_agent_shuts_the_deployment_down(deployment: Deployment) -> None:
    async def agent() -> Any:
        async with mcp_client(deployment.url, read_timeout_seconds=60) as c:
            return await call(c, "shutdown")

    out = asyncio.run(asyncio.wait_for(agent(), 120))
    assert out["state"] == "shutting down"
    assert deployment.boot.proc.wait(180) == 0, deployment.boot.output()[-3000:]
    deployment.boot.wait_all_exited(60)
    assert "shutting down" in deployment.boot.output()


async def _state_is(c: Client, entry: str, state: str) -> bool:
    return (await services(c)).get(entry, {}).get("state") == state


async def _all_active(c: Client) -> bool:
    return all(s["state"] == "active" for s in (await services(c)).values())


async def _has_tools(c: Client, want: set[str]) -> set[str] | None:
    names = await tool_names(c)
    return names if want <= names else None


async def _integrated_more(c: Client, n: int) -> bool:
    return (await slam_stats(c))["engine"]["scans_integrated"] > n
