"""MCP gateway benchmark: what going through the one endpoint costs an agent.

    python bench/gateway_bench.py [--calls 200] [--out bench/results/gateway.json]

An in-process atlas, a provider with one MCP tool (answering at once) and the gateway, all in this
process (they share one GIL, so figures are upper bounds). Measures, with the official MCP client on a
persistent session: a tool call straight to the provider, the same call through the gateway, the
gateway's tools/list, a lifecycle verb (list_services), and how long after a provider registers the
gateway announces it (tools/list_changed; bounded by the 1 s atlas poll).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import platform
import sys
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:  # runnable as a plain script from a checkout
    sys.path.insert(0, str(REPO))

from mcp import Client  # noqa: E402

from atlas.server import AtlasServer  # noqa: E402
from rbnx.gateway import Entry, Gateway, LifecycleControl  # noqa: E402
from robonix_api import Ok, Service  # noqa: E402
from robonix_api.proto_gen import navigation_pb2  # noqa: E402

NAV = "robonix/service/navigation/navigate"
ARGS = {"goal": {"pose": {"position": {"x": 1.0}}}}


def stats_ms(xs: list[float]) -> dict[str, float]:
    xs = sorted(xs)
    pick = lambda q: xs[min(len(xs) - 1, int(q * len(xs)))] * 1000  # noqa: E731
    return {"p50_ms": round(pick(0.5), 2), "p95_ms": round(pick(0.95), 2), "p99_ms": round(pick(0.99), 2),
            "n": len(xs)}


def provider(atlas: str, pid: str) -> Service:
    svc = Service(pid, "robonix/service/navigation", atlas=atlas)
    svc.on_init(lambda cfg: Ok())

    @svc.mcp(NAV)
    def navigate(req: navigation_pb2.Navigate_Request) -> navigation_pb2.Navigate_Response:
        """Accept any goal at once."""
        return navigation_pb2.Navigate_Response(accepted=True, run_id="r", detail="ok")

    svc.run_in_thread()
    return svc


async def timed(n: int, fn: Any) -> list[float]:
    await fn()  # warm-up
    out = []
    for _ in range(n):
        t = time.perf_counter()
        await fn()
        out.append(time.perf_counter() - t)
    return out


async def run(args: argparse.Namespace, atlas: str, gw: Gateway, svcs: list[Service]) -> dict[str, Any]:
    svcs.append(provider(atlas, "bench"))
    res: dict[str, Any] = {}
    async with Client(gw.url) as c:
        async with c.listen(tools_list_changed=True) as sub:
            t0 = time.perf_counter()
            svcs.append(provider(atlas, "bench2"))
            while True:  # the first provider may be announced first: wait for the second one
                await asyncio.wait_for(sub.__anext__(), 30)
                if "bench2.navigate" in {t.name for t in (await c.list_tools()).tools}:
                    break
            res["announce_after_register_s"] = round(time.perf_counter() - t0, 3)
        url = gw._tools["bench.navigate"].url
        async with Client(url) as direct:
            res["direct_call"] = stats_ms(await timed(args.calls, lambda: direct.call_tool("navigate", ARGS)))
        res["gateway_call"] = stats_ms(await timed(args.calls, lambda: c.call_tool("bench.navigate", ARGS)))
        res["gateway_list_tools"] = stats_ms(await timed(args.calls, lambda: c.list_tools(cache_mode="refresh")))
        res["gateway_list_services"] = stats_ms(await timed(args.calls, lambda: c.call_tool("list_services", {})))
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=200)
    ap.add_argument("--out", default=str(REPO / "bench" / "results" / "gateway.json"))
    args = ap.parse_args()
    server = AtlasServer(listen="127.0.0.1:0")
    atlas = server.start()
    gw = Gateway(atlas, LifecycleControl(atlas, [Entry("bench", "service", {})]))
    gw.start()
    svcs: list[Service] = []
    try:
        res = asyncio.run(run(args, atlas, gw, svcs))
    finally:
        for s in svcs:
            s.stop()
        gw.stop()
        server.stop()
    res["machine"] = {"python": platform.python_version(), "cpus": __import__("os").cpu_count()}
    for k in ("direct_call", "gateway_call", "gateway_list_tools", "gateway_list_services"):
        r = res[k]
        print(f"{k:<24} p50 {r['p50_ms']:7.2f} ms   p95 {r['p95_ms']:7.2f} ms   p99 {r['p99_ms']:7.2f} ms")
    print(f"{'announce after register':<24} {res['announce_after_register_s']:.3f} s")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=2))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
