"""Atlas latency benchmark: Query (by contract_id) and ConnectCapability with 1000 declared capabilities.

    python bench/atlas_bench.py [--out bench/results/atlas.json] [--calls 2000] [--in-process]

By default the atlas runs as its own process (as under ``rbnx boot``), so the client and the server do
not share a GIL; ``--in-process`` runs it in this process instead. Goals (issue 2): p50 <= 1 ms and
p99 <= 3 ms on loopback. More sections (e.g. boot-to-ACTIVE timing) plug into ``SECTIONS``: each is a
function ``(BenchContext) -> dict`` whose result lands under its name in the JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import queue
import random
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import grpc

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:  # runnable as a plain script from a checkout
    sys.path.insert(0, str(REPO))

from robonix_api.atlas_client import AtlasClient  # noqa: E402
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc  # noqa: E402
from robonix_api.types import GrpcParams, McpParams, Ros2Params, Transport  # noqa: E402

GOAL_P50_MS = 1.0
GOAL_P99_MS = 3.0


@dataclass
class BenchContext:
    """What every section may use: the atlas address, clients, the declared capabilities, CLI args."""

    address: str
    args: argparse.Namespace
    client: AtlasClient
    stub: atlas_pb2_grpc.AtlasStub
    declared: list[tuple[str, str, Transport]] = field(
        default_factory=list
    )  # (provider, contract, transport)
    contracts: list[str] = field(default_factory=list)
    rng: random.Random = field(default_factory=lambda: random.Random(1234))


def stats_ms(samples_s: list[float]) -> dict[str, float]:
    """Percentiles in milliseconds (nearest-rank, no interpolation, so p99 is a real sample)."""
    xs = sorted(samples_s)
    n = len(xs)

    def pct(p: float) -> float:
        return xs[min(n - 1, max(0, int(round(p / 100.0 * n + 0.5)) - 1))] * 1000.0

    return {
        "n": n,
        "p50_ms": round(pct(50), 4),
        "p90_ms": round(pct(90), 4),
        "p99_ms": round(pct(99), 4),
        "mean_ms": round(sum(xs) / n * 1000.0, 4),
        "max_ms": round(xs[-1] * 1000.0, 4),
    }


def timed(fn: Callable[[], Any], calls: int, warmup: int) -> list[float]:
    for _ in range(warmup):
        fn()
    out = []
    clock = time.perf_counter
    for _ in range(calls):
        t0 = clock()
        fn()
        out.append(clock() - t0)
    return out


# --------------------------------------------------------------------------- atlas process


class AtlasProcess:
    """The atlas as a child process (stopped by PID) or in-process; ``address`` once started."""

    def __init__(self, in_process: bool) -> None:
        self.in_process = in_process
        self.address = ""
        self._proc: subprocess.Popen | None = None
        self._server: Any = None

    def start(self, timeout: float = 60.0) -> str:
        if self.in_process:
            from atlas.server import AtlasServer

            self._server = AtlasServer("127.0.0.1:0", heartbeat_timeout_ms=0)
            self.address = self._server.start()
            return self.address
        env = dict(
            os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))
        )
        cmd = [sys.executable, "-m", "atlas.server", "--listen", "127.0.0.1:0", "--heartbeat-timeout-ms", "0"]
        cmd += ["--log-level", "WARNING"]
        self._proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env, cwd=str(REPO))
        lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=lambda: lines.put(self._proc.stdout.readline()), daemon=True).start()
        try:
            line = lines.get(timeout=timeout)
        except queue.Empty:
            self.stop()
            raise RuntimeError("atlas did not report ready in time") from None
        if not line.startswith("atlas listening on "):
            self.stop()
            raise RuntimeError(f"unexpected atlas output: {line!r}")
        self.address = line.split()[-1]
        return self.address

    def stop(self) -> None:
        if self._server is not None:
            self._server.stop(0)
            self._server = None
        if self._proc is not None:
            if self._proc.poll() is None:
                self._proc.send_signal(signal.SIGTERM)
                try:
                    self._proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self._proc.kill()
                    self._proc.wait()
            self._proc = None


# --------------------------------------------------------------------------- sections


def populate(ctx: BenchContext) -> dict[str, Any]:
    """Register providers and declare ``providers x caps_per_provider`` capabilities; each contract id is
    shared by several providers so a Query returns a realistic handful, mixing all three transports."""
    a = ctx.args
    n_contracts = max(1, a.providers * a.caps_per_provider // a.providers_per_contract)
    ctx.contracts = [f"bench/contract_{k:04d}" for k in range(n_contracts)]
    t0 = time.perf_counter()
    for i in range(a.providers):
        pid = f"bench-provider-{i:04d}"
        ctx.client.register_service(pid, "bench")
        for j in range(a.caps_per_provider):
            cid = ctx.contracts[(i * a.caps_per_provider + j) % n_contracts]
            transport = (Transport.ROS2, Transport.GRPC, Transport.MCP)[(i + j) % 3]
            if transport == Transport.ROS2:
                ep, params = "", Ros2Params("reliable")  # minted
            elif transport == Transport.GRPC:
                ep, params = f"127.0.0.1:{20000 + i}", GrpcParams("robonix_contracts.proto", "Bench", "Call")
            else:
                ep, params = f"http://127.0.0.1:{30000 + i}/mcp/", McpParams('{"type": "object"}')
            ctx.client.declare_capability(pid, cid, ep, transport, params)
            ctx.declared.append((pid, cid, transport))
    elapsed = time.perf_counter() - t0
    return {
        "providers": a.providers,
        "capabilities": len(ctx.declared),
        "contracts": n_contracts,
        "providers_per_contract": a.providers_per_contract,
        "seconds": round(elapsed, 3),
        "declare_per_s": round(len(ctx.declared) / elapsed, 1),
    }


def measure_query(ctx: BenchContext) -> dict[str, Any]:
    """Query by contract_id through the raw stub (wire latency) and through AtlasClient (typed)."""
    rng = ctx.rng
    contracts = ctx.contracts

    def raw() -> None:
        resp = ctx.stub.Query(atlas_pb2.QueryRequest(contract_id=rng.choice(contracts)), timeout=10)
        assert resp.providers

    def typed() -> None:
        assert ctx.client.query(contract_id=rng.choice(contracts))

    sample = ctx.client.query(contract_id=contracts[0])
    return {
        "providers_per_reply": len(sample),
        "raw_stub": stats_ms(timed(raw, ctx.args.calls, ctx.args.warmup)),
        "atlas_client": stats_ms(timed(typed, ctx.args.calls, ctx.args.warmup)),
    }


def measure_connect(ctx: BenchContext) -> dict[str, Any]:
    """ConnectCapability to a random declared capability; each channel is closed (untimed) right after,
    as consumers do, so the channel table stays small."""
    rng = ctx.rng
    opened: list[str] = []

    def connect() -> None:
        pid, cid, transport = rng.choice(ctx.declared)
        req = atlas_pb2.ConnectCapabilityRequest(
            consumer_id="bench-consumer", provider_id=pid, contract_id=cid, transport=int(transport)
        )
        opened.append(ctx.stub.ConnectCapability(req, timeout=10).channel_id)

    samples: list[float] = []
    clock = time.perf_counter
    for k in range(ctx.args.warmup + ctx.args.calls):
        t0 = clock()
        connect()
        dt = clock() - t0
        ctx.stub.DisconnectCapability(
            atlas_pb2.DisconnectCapabilityRequest(channel_id=opened.pop()), timeout=10
        )
        if k >= ctx.args.warmup:
            samples.append(dt)
    return {"raw_stub": stats_ms(samples)}


#: (name, function) in run order; append more sections here (e.g. ("boot", measure_boot)).
SECTIONS: list[tuple[str, Callable[[BenchContext], dict[str, Any]]]] = [
    ("populate", populate),
    ("query", measure_query),
    ("connect", measure_connect),
]


def goals(results: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {"p50_ms_max": GOAL_P50_MS, "p99_ms_max": GOAL_P99_MS}
    ok = True
    for name in ("query", "connect"):
        st = results.get(name, {}).get("raw_stub")
        if st:
            met = st["p50_ms"] <= GOAL_P50_MS and st["p99_ms"] <= GOAL_P99_MS
            out[name] = met
            ok = ok and met
    out["all_met"] = ok
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "results" / "atlas.json")
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--providers", type=int, default=100)
    ap.add_argument("--caps-per-provider", type=int, default=10)
    ap.add_argument("--providers-per-contract", type=int, default=5)
    ap.add_argument("--in-process", action="store_true", help="run the atlas in this process")
    a = ap.parse_args(argv)

    atlas = AtlasProcess(a.in_process)
    results: dict[str, Any] = {
        "benchmark": "atlas",
        "atlas": "in-process" if a.in_process else "subprocess",
        "host": {"python": platform.python_version(), "grpc": grpc.__version__, "cpus": os.cpu_count()},
        "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    try:
        address = atlas.start()
        client = AtlasClient(address)
        channel = grpc.insecure_channel(address, options=[("grpc.enable_http_proxy", 0)])
        ctx = BenchContext(address, a, client, atlas_pb2_grpc.AtlasStub(channel))
        try:
            for name, fn in SECTIONS:
                results[name] = fn(ctx)
                print(f"{name}: {json.dumps(results[name])}", flush=True)
        finally:
            channel.close()
            client.close()
    finally:
        atlas.stop()

    results["goals"] = goals(results)
    for name in ("query", "connect"):
        st = results[name]["raw_stub"]
        print(f"{name:8s} p50 {st['p50_ms']:.3f} ms  p99 {st['p99_ms']:.3f} ms  (n={st['n']})")
    print(
        f"goals (p50 <= {GOAL_P50_MS} ms, p99 <= {GOAL_P99_MS} ms): "
        f"{'met' if results['goals']['all_met'] else 'NOT met'}"
    )
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
