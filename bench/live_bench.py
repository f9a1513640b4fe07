"""Issue 19 figures: dashboard update latency and the CPU cost of recording (and, with --roundtrip, the
replay round trip's map IoU / ATE difference).

1. Dashboard latency (goal p50 ≤ 100 ms): the dashboard serves a DDS domain of its own; this script
   publishes TF odom->base_link with a new x every 50 ms (wall-clock stamp taken at publish) and headless
   Debian chromium records when the page drew each pose (``window.__dash.drawLog``, epoch ms from
   ``performance.timeOrigin``); latency = drawn - published, same machine, same clock.
2. Recording overhead (goal ≤ 10 %): `rbnx boot` of the sim deploy (kitchen, rtf 3, robot idle: the
   deploy's smallest CPU use, so the ratio is conservative); CPU seconds of the deploy's processes over a
   window without recording, then of `rbnx record` (default topics) over an equal window while it runs.
   Overhead = recorder CPU / deploy CPU in the recording window.
3. --roundtrip: `rbnx demo --record` (kitchen, 2 goals) replayed into a fresh slam_service.

    python bench/live_bench.py [--window 20] [--samples 400] [--roundtrip]

Prints the figures and writes bench/results/live.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
RESULTS = REPO / "bench" / "results" / "live.json"
SIM_DEPLOY = REPO / "examples" / "sim" / "deploy.yaml"

from support.boot import RbnxBoot, rbnx_cmd  # noqa: E402
from support.browser import free_port, launch  # noqa: E402

from rbnx.demo.boot import pick_domain_id  # noqa: E402


def _pct(v: list[float], q: float) -> float:
    s = sorted(v)
    return s[min(len(s) - 1, int(q * len(s)))]


def dashboard_latency(samples: int) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    from rbnx.dashboard.launch import start_background
    from robonix_api.dds import DdsNode, OccupancyGrid, StaticTfBroadcaster, TfBroadcaster
    from robonix_api.dds.convert import header

    domain = pick_domain_id()
    port = free_port()
    dash = start_background("", port, domain)  # no atlas: only the DDS side is measured
    node = DdsNode(domain_id=domain, name="latency_bench")
    published: dict[float, float] = {}
    try:
        grid = OccupancyGrid(header=header(0.0, "map"))
        grid.info.resolution, grid.info.width, grid.info.height = 0.05, 200, 200
        grid.info.origin.position.x = grid.info.origin.position.y = -5.0
        grid.data = [0] * (200 * 200)
        map_pub = node.create_publisher("/map", OccupancyGrid, "latched")
        map_pub.publish(grid)
        StaticTfBroadcaster(node).send("map", "odom", 0.0, 0.0, 0.0)
        tf = TfBroadcaster(node)
        with sync_playwright() as pw:
            browser = launch(pw)
            page = browser.new_page(viewport={"width": 1300, "height": 800})
            page.goto(dash.url)
            tf.send("odom", "base_link", 0.0, 0.0, 0.0, time.time())
            page.wait_for_function("window.__dash.mapVersion > 0 && window.__dash.drawnPose !== null", timeout=60_000)
            for i in range(1, samples + 1):
                x = round(-4.0 + 8.0 * i / samples, 4)
                t = time.time()
                tf.send("odom", "base_link", x, 0.5, 0.0, t)
                published[x] = t * 1000.0
                threading.Event().wait(0.05)
            threading.Event().wait(1.0)
            log = page.evaluate("window.__dash.drawLog")
            browser.close()
    finally:
        node.close()
        dash.stop()
    drawn: dict[float, float] = {}
    for e in log:
        drawn.setdefault(round(e["x"], 4), e["t"])
    lat = [drawn[x] - t for x, t in published.items() if x in drawn]
    return {"samples": len(published), "drawn": len(lat), "p50_ms": round(_pct(lat, 0.5), 1),
            "p95_ms": round(_pct(lat, 0.95), 1), "max_ms": round(max(lat), 1), "goal_p50_ms": 100}


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def recording_overhead(window: float) -> dict[str, Any]:
    saved = dict(os.environ)
    os.environ.update(RBNX_SIM_SCENE="kitchen", RBNX_SIM_RTF="3", ROS_DOMAIN_ID=str(pick_domain_id()))
    try:
        with tempfile.TemporaryDirectory(prefix="live-bench-") as tmp_s:
            tmp = Path(tmp_s)
            with RbnxBoot(SIM_DEPLOY, tmp) as boot:
                try:
                    boot.wait_ready(3, 240)
                    st = boot.state()
                    pids = [st["atlas_proc"]["pid"], *(c["pid"] for c in st["children"])]
                    threading.Event().wait(5.0)
                    a = sum(_cpu_s(p) for p in pids)
                    threading.Event().wait(window)
                    base = sum(_cpu_s(p) for p in pids) - a
                    t_rec = time.monotonic()
                    rec = subprocess.Popen(rbnx_cmd() + ["record", "-o", str(tmp / "bench.mcap"), "-q"],
                                           stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
                    threading.Event().wait(5.0)  # imports and discovery are start-up, not steady state
                    a, r0 = sum(_cpu_s(p) for p in pids), _cpu_s(rec.pid)
                    threading.Event().wait(window)
                    with_rec = sum(_cpu_s(p) for p in pids) - a
                    rec_cpu = _cpu_s(rec.pid) - r0
                    rec.send_signal(signal.SIGINT)
                    rec.wait(60)
                    size = (tmp / "bench.mcap").stat().st_size / (time.monotonic() - t_rec)
                finally:
                    boot.interrupt()
                    boot.wait_all_exited()
    finally:
        os.environ.clear()
        os.environ.update(saved)
    return {"window_s": window, "deploy_cpu_s_without": round(base, 2), "deploy_cpu_s_with": round(with_rec, 2),
            "recorder_cpu_s": round(rec_cpu, 2), "overhead_pct": round(100 * rec_cpu / with_rec, 1),
            "mcap_bytes_per_s": round(size), "goal_pct": 10}


def roundtrip() -> dict[str, Any]:
    from support.replay_roundtrip import replay_into_fresh_slam

    from rbnx.replay_eval import compare, load_run

    with tempfile.TemporaryDirectory(prefix="live-bench-rt-") as tmp_s:
        tmp = Path(tmp_s)
        r = subprocess.run(rbnx_cmd() + ["demo", "--scene", "kitchen", "--goals", "2", "--rtf", "3", "--record",
                                         "--out", str(tmp / "demo")], capture_output=True, text=True, timeout=900)
        if r.returncode != 0:
            raise SystemExit(f"rbnx demo failed:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
        session, info = replay_into_fresh_slam(tmp / "demo" / "run.mcap", tmp / "replay", rate=1 / 3)  # 1x sim
        m = compare(load_run(tmp / "demo" / "run.mcap"), load_run(session))
    return {k: round(v, 4) for k, v in m.items()} | {"replay_wall_s": round(info["replay_wall_s"], 1)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--window", type=float, default=20.0, help="CPU measuring window in seconds (default 20)")
    ap.add_argument("--samples", type=int, default=400, help="poses for the latency figure (default 400)")
    ap.add_argument("--roundtrip", action="store_true", help="also run the replay round trip (~2 min)")
    args = ap.parse_args()
    os.environ.setdefault("CYCLONEDDS_URI", (REPO / "config" / "cyclonedds_loopback.xml").as_uri())
    result: dict[str, Any] = {"host": {"python": platform.python_version(), "cpus": os.cpu_count(),
                                       "machine": platform.machine()}}
    result["dashboard_latency"] = lat = dashboard_latency(args.samples)
    print(f"dashboard pose latency (DDS -> drawn): p50 {lat['p50_ms']} ms, p95 {lat['p95_ms']} ms "
          f"({lat['drawn']}/{lat['samples']} poses drawn; goal p50 <= 100 ms)", flush=True)
    result["recording_overhead"] = rec = recording_overhead(args.window)
    print(f"recording: {rec['recorder_cpu_s']} CPU-s vs deploy {rec['deploy_cpu_s_with']} CPU-s over "
          f"{args.window:g} s = {rec['overhead_pct']} % (goal <= 10 %); {rec['mcap_bytes_per_s'] / 1e3:.0f} kB/s",
          flush=True)
    if args.roundtrip:
        result["roundtrip"] = rt = roundtrip()
        print(f"replay round trip: map IoU {rt['map_iou']} (exact {rt['map_iou_exact']}), ATE live "
              f"{rt['ate_live_m'] * 100:.2f} cm, replay {rt['ate_replay_m'] * 100:.2f} cm, "
              f"diff {rt['ate_diff_m'] * 100:.3f} cm", flush=True)
    result["goals_met"] = lat["p50_ms"] <= 100 and rec["overhead_pct"] <= 10
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(result, indent=2) + "\n")
    print(f"goals {'met' if result['goals_met'] else 'NOT met'} -> {RESULTS.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
