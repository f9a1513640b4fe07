"""Channel leases and caps: a ConnectCapability flood cannot grow the atlas without bound, and
``rbnx channels`` / ``rbnx inspect`` keep answering after it. A real ``robonix-atlas`` process (no token:
robonix's open atlas, where anyone may connect), memory read from /proc."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import grpc
from support.procs import wait_until

from atlas.registry import MAX_CHANNELS, Registry
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc
from robonix_api.types import GrpcParams, Kind, Transport

NAV = "robonix/service/navigation/navigate"
FLOOD = 30_000


def _rss_kb(pid: int) -> int:
    text = Path(f"/proc/{pid}/status").read_text()
    return int(re.search(r"VmRSS:\s+(\d+)", text).group(1))  # type: ignore[union-attr]


def _atlas_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "robonix-atlas"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "atlas.server"]


def _rbnx(*args: str) -> subprocess.CompletedProcess[str]:
    exe = Path(sys.executable).parent / "rbnx"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]
    return subprocess.run(cmd + list(args), capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)


def _connect_many(stub: atlas_pb2_grpc.AtlasStub, n: int, tag: str, batch: int = 256) -> None:
    for start in range(0, n, batch):
        futs = [stub.ConnectCapability.future(atlas_pb2.ConnectCapabilityRequest(
                    consumer_id=f"{tag}-{i % 997}", provider_id="nav2", contract_id=NAV,
                    transport=atlas_pb2.TRANSPORT_GRPC), timeout=30)
                for i in range(start, min(n, start + batch))]
        for f in futs:
            f.result()


def test_connect_flood_is_bounded_and_listing_still_works(tmp_path: Path) -> None:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    env.pop("ROBONIX_DEPLOY_TOKEN", None)
    log = tmp_path / "atlas.log"
    with open(log, "w") as fh:
        proc = subprocess.Popen(_atlas_cmd() + ["--listen", "127.0.0.1:0", "--heartbeat-timeout-ms", "0"],
                                env=env, stdout=fh, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        wait_until(lambda: "atlas listening on" in log.read_text() or proc.poll() is not None, 30, "atlas up")
        addr = re.search(r"atlas listening on (\S+)", log.read_text()).group(1)  # type: ignore[union-attr]
        with grpc.insecure_channel(addr, options=[("grpc.enable_http_proxy", 0)]) as ch:
            stub = atlas_pb2_grpc.AtlasStub(ch)
            stub.RegisterService(atlas_pb2.RegisterRequest(id="nav2", namespace="robonix/service/navigation"),
                                 timeout=10)
            req = atlas_pb2.DeclareCapabilityRequest(provider_id="nav2", contract_id=NAV, endpoint="127.0.0.1:5555",
                                                     transport=atlas_pb2.TRANSPORT_GRPC)
            req.params.grpc.service_name = "RobonixServiceNavigationNavigate"
            req.params.grpc.method = "Navigate"
            stub.DeclareCapability(req, timeout=10)
            _connect_many(stub, 2_000, "warmup")  # gRPC's own buffers and threads reach their working size
            before = _rss_kb(proc.pid)
            t0 = time.monotonic()
            _connect_many(stub, FLOOD, "flood")
            took = time.monotonic() - t0
            after = _rss_kb(proc.pid)
            snap = stub.InspectAtlas(atlas_pb2.InspectAtlasRequest(), timeout=10)
        import json

        data = json.loads(snap.json)
        print(f"flood: {FLOOD} ConnectCapability in {took:.1f}s; atlas RSS {before / 1024:.1f} -> "
              f"{after / 1024:.1f} MB ({100.0 * (after - before) / before:+.1f} %); channels held "
              f"{data['channels_total']} (cap {MAX_CHANNELS}), listed {len(data['channels'])}, "
              f"InspectAtlas reply {len(snap.json) / 1024:.0f} kB")
        assert data["channels_total"] <= MAX_CHANNELS
        assert after <= before * 1.10, (before, after)
        for args in (["channels"], ["inspect"]):
            r = _rbnx("--atlas", addr, *args)
            assert r.returncode == 0, r.stderr
            assert "nav2" in r.stdout
    finally:
        proc.terminate()
        proc.wait(30)


def test_lease_expires_unless_renewed_by_the_consumers_heartbeat() -> None:
    now = [1000.0]
    reg = Registry(heartbeat_timeout_ms=0, clock=lambda: now[0], channel_lease_ms=300_000,
                   max_channels_per_consumer=4, max_channels=10)
    reg.register(Kind.SERVICE, "nav2", "robonix/service/navigation")
    reg.declare("nav2", NAV, Transport.GRPC, "127.0.0.1:5555", GrpcParams(service_name="S", method="M"))
    reg.register(Kind.SERVICE, "agent", "robonix/skill/agent")
    kept = reg.connect("agent", "nav2", NAV, Transport.GRPC)  # a registered consumer: its heartbeat renews
    reg.connect("oneshot", "nav2", NAV, Transport.GRPC)
    now[0] += 200
    reg.heartbeat("agent")
    now[0] += 150  # "oneshot" is 350 s old, "agent"'s channel was renewed 150 s ago
    reg.sweep()
    snap = reg.snapshot()
    assert [c["channel_id"] for c in snap["channels"]] == [kept.channel_id]

    for _ in range(6):  # per-consumer cap: the stalest of the consumer's own go first
        reg.connect("greedy", "nav2", NAV, Transport.GRPC)
    assert reg.channel_count() == 1 + 4
    for i in range(20):  # global cap
        reg.connect(f"c{i}", "nav2", NAV, Transport.GRPC)
    assert reg.channel_count() == 10
    assert reg.channels_evicted >= 2 + 15
