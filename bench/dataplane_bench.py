"""Data-plane figures between two processes: scan latency, scan throughput, grid publish+deliver time.

One command: ``python bench/dataplane_bench.py`` (prints the figures, writes bench/results/dataplane.json).
It uses its own ROS_DOMAIN_ID and the loopback-only Cyclone config, and prints the effective config so
the run documents that multicast is off and only ``lo`` is used. Latency is one-way: the publisher puts
CLOCK_MONOTONIC (system-wide on Linux) into header.stamp, the receiving process subtracts it on delivery
(after deserialisation, inside the callback).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
RESULTS = REPO / "bench" / "results" / "dataplane.json"


def _stamp_now():  # -> Time, imported lazily so env is set first
    from robonix_api.dds import Time

    ns = time.monotonic_ns()
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def _age_ms(stamp) -> float:
    return (time.monotonic_ns() - (stamp.sec * 1_000_000_000 + stamp.nanosec)) / 1e6


def sink() -> None:
    """Child process: record per-topic delivery delays, print them as JSON when told to stop (stdin EOF)."""
    from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid

    node = DdsNode(name="bench_sink")
    lat: dict[str, list[float]] = {"scan": [], "burst": [], "grid": []}
    grid_sizes: list[int] = []

    def on_scan(m: LaserScan) -> None:
        lat["burst" if m.header.frame_id == "burst" else "scan"].append(_age_ms(m.header.stamp))

    def on_grid(m: OccupancyGrid) -> None:
        lat["grid"].append(_age_ms(m.header.stamp))
        grid_sizes.append(int(m.data.size))

    node.create_subscription("/bench/scan", LaserScan, on_scan, "best_effort", depth=1000)
    node.create_subscription("/bench/map", OccupancyGrid, on_grid, "reliable", depth=2)
    print("READY", flush=True)
    for line in sys.stdin:
        if line.strip() == "COUNTS":
            print(json.dumps({k: len(v) for k, v in lat.items()}), flush=True)
    print(json.dumps({"lat": lat, "grid_sizes": grid_sizes}), flush=True)
    node.close()


def _stats(xs: list[float]) -> dict[str, float]:
    a = np.asarray(xs, dtype=float)
    if a.size == 0:
        return {"n": 0}
    return {"n": int(a.size), "p50_ms": float(np.percentile(a, 50)), "p99_ms": float(np.percentile(a, 99)),
            "max_ms": float(a.max()), "mean_ms": float(a.mean())}


def serializer_comparison() -> dict[str, dict[str, float]]:
    """In-process: cyclonedds' stock sequence<int8> machine vs our numpy fast path (why the fast path exists)."""
    from cyclonedds.idl._support import Buffer

    from robonix_api.dds import OccupancyGrid

    fast = OccupancyGrid.__idl__.v1_machine.members_machines["data"]
    out: dict[str, dict[str, float]] = {}
    for n in (400, 2000):
        data = np.random.default_rng(1).integers(-1, 101, size=n * n).astype(np.int8)
        for name, machine, value in (("stock", fast.orig, data.tolist()), ("fast", fast, data)):
            buf = Buffer()
            t = time.perf_counter()
            machine.serialize(buf, value)
            ser = time.perf_counter() - t
            rd = Buffer(buf.asbytes())
            t = time.perf_counter()
            machine.deserialize(rd)
            out[f"{name}_{n}x{n}"] = {"serialize_ms": ser * 1e3, "deserialize_ms": (time.perf_counter() - t) * 1e3}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scans", type=int, default=1000, help="scans at 100 Hz for the latency figure")
    ap.add_argument("--burst-s", type=float, default=2.0, help="seconds of back-to-back scans")
    ap.add_argument("--grids", type=int, default=10, help="grids of each size")
    ap.add_argument("--role", default="main", choices=["main", "sink"])
    args = ap.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", str(150 + os.getpid() % 80))
    os.environ.setdefault("CYCLONEDDS_URI", (REPO / "config" / "cyclonedds_loopback.xml").as_uri())
    if args.role == "sink":
        sink()
        return 0

    from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid, effective_config
    from robonix_api.dds.config import probe_runtime
    from robonix_api.dds.convert import laser_scan

    cfg = effective_config()
    print(f"domain {os.environ['ROS_DOMAIN_ID']}, config {cfg['uri']}")
    print(f"effective config: interfaces={cfg['interfaces']} allow_multicast={cfg['allow_multicast']} "
          f"peers={cfg['peers']} loopback_only={cfg['loopback_only']}")
    rt = probe_runtime()
    print(f"Cyclone's own trace: {rt['trace_line']} (AllowMulticast={rt['allow_multicast']})")
    cfg["runtime"] = rt
    if not (cfg["multicast_disabled"] and cfg["loopback_only"] and rt["selected_interfaces"] == ["lo"]):
        print("WARNING: config is not loopback-only/multicast-off")
    child = subprocess.Popen([sys.executable, __file__, "--role", "sink"], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True, env=os.environ.copy())
    node = DdsNode(name="bench_main")
    try:
        assert child.stdout.readline().strip() == "READY"
        scan_pub = node.create_publisher("/bench/scan", LaserScan, "best_effort", depth=1000)
        grid_pub = node.create_publisher("/bench/map", OccupancyGrid, "reliable", depth=2)
        if not (scan_pub.wait_for_subscribers(1, 20) and grid_pub.wait_for_subscribers(1, 20)):
            raise RuntimeError("sink process never matched")
        time.sleep(0.5)
        scan = laser_scan(np.linspace(0.5, 10.0, 360), -np.pi, 2 * np.pi / 360, range_min=0.05, range_max=12.0)

        # 1) latency at 100 Hz
        t_next = time.monotonic()
        for _ in range(args.scans):
            t_next += 0.01
            scan.header.stamp = _stamp_now()
            scan_pub.publish(scan)
            time.sleep(max(0.0, t_next - time.monotonic()))
        time.sleep(0.3)

        # 2) max rate, back to back
        scan.header.frame_id = "burst"
        sent, t0 = 0, time.monotonic()
        while time.monotonic() - t0 < args.burst_s:
            scan.header.stamp = _stamp_now()
            scan_pub.publish(scan)
            sent += 1
        burst_s = time.monotonic() - t0
        time.sleep(0.5)

        # 3) grids: one at a time, each delivered before the next
        pub_times: dict[str, list[float]] = {}
        for n in (400, 2000):
            data = np.random.default_rng(0).integers(-1, 101, size=n * n).astype(np.int8)
            msg = OccupancyGrid(data=data)
            msg.info.width = msg.info.height = n
            msg.info.resolution = 0.05
            for _ in range(args.grids):
                child.stdin.write("COUNTS\n")
                child.stdin.flush()
                before = json.loads(child.stdout.readline())["grid"]
                msg.header.stamp = _stamp_now()
                t = time.perf_counter()
                grid_pub.publish(msg)
                pub_times.setdefault(f"{n}x{n}", []).append((time.perf_counter() - t) * 1e3)
                deadline = time.monotonic() + 10
                while time.monotonic() < deadline:
                    child.stdin.write("COUNTS\n")
                    child.stdin.flush()
                    if json.loads(child.stdout.readline())["grid"] > before:
                        break
                    time.sleep(0.005)
        child.stdin.close()
        res = json.loads(child.stdout.readline())
    finally:
        node.close()
        if child.poll() is None:
            try:
                child.wait(timeout=20)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()

    g = res["lat"]["grid"]
    want = [400 * 400] * args.grids + [2000 * 2000] * args.grids
    if res["grid_sizes"] != want:
        print(f"WARNING: grids delivered {len(res['grid_sizes'])}/{len(want)} or with wrong sizes")
    ser = serializer_comparison()
    k = args.grids
    out = {
        "config": {k2: cfg[k2] for k2 in ("uri", "interfaces", "allow_multicast", "peers", "loopback_only", "runtime")},
        "domain_id": int(os.environ["ROS_DOMAIN_ID"]),
        "scan_latency_100hz": _stats(res["lat"]["scan"]) | {"sent": args.scans},
        "scan_max_rate": {"sent": sent, "received": len(res["lat"]["burst"]), "seconds": burst_s,
                          "sent_per_s": sent / burst_s, "received_per_s": len(res["lat"]["burst"]) / burst_s},
        "grid_400x400": _stats(g[:k]) | {"publish_call_ms_median": float(np.median(pub_times["400x400"]))},
        "grid_2000x2000": _stats(g[k:2 * k]) | {"publish_call_ms_median": float(np.median(pub_times["2000x2000"]))},
        "grids_delivered_intact": res["grid_sizes"] == want,
        "int8_serializer_ms": ser,
        "goals": {"scan_p99_ms": 2.0, "grid_400_ms": 20.0, "grid_2000_ms": 200.0},
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(out, indent=2))
    s, r = out["scan_latency_100hz"], out["scan_max_rate"]
    print(f"scan 360 beams @100 Hz, one-way: p50 {s.get('p50_ms', float('nan')):.3f} ms, "
          f"p99 {s.get('p99_ms', float('nan')):.3f} ms ({s['n']}/{args.scans} delivered)")
    print(f"max scans/s: sent {r['sent_per_s']:.0f}/s, received {r['received_per_s']:.0f}/s")
    for name in ("grid_400x400", "grid_2000x2000"):
        gg = out[name]
        print(f"{name} publish+deliver: median {gg.get('p50_ms', float('nan')):.1f} ms, "
              f"max {gg.get('max_ms', float('nan')):.1f} ms (publish() call {gg['publish_call_ms_median']:.1f} ms)")
    for key, v in ser.items():
        print(f"int8 data {key}: serialize {v['serialize_ms']:.1f} ms, deserialize {v['deserialize_ms']:.1f} ms")
    print(f"wrote {RESULTS}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
