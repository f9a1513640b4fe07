"""SLAM provider scan path at the lidar's rate: scans dropped, queue depth and per-scan latency, measured.

One command: ``python bench/slam_provider_drops.py`` (prints a table, writes
bench/results/slam_provider_drops.json). For each MuJoCo scene (apartment, warehouse) the scripted loop of
robonix_eval.slam_loop is driven once in the in-process sim and its lidar scans, odometry and truth are
kept. They are then replayed at 10 Hz in WALL time over DDS (loopback, a domain of its own) into the
service's real scan path: :class:`slam_service.loop.SlamLoop` (subscription -> ScanQueue -> worker ->
SlamEngine -> map->odom), built with the provider's default config (queue of 4, same frames, sim time),
with /clock, odom->base_link on /tf, base_link->laser on /tf_static and /odom published like the HAL does.

Figures per scene: scans sent / received / processed / dropped by the queue (``scans_dropped_behind``,
the issue-20 acceptance figure) / skipped, the queue's high-water mark, per-scan latency (arrival in the
callback -> pose out, which includes queue waiting) and ``SlamEngine.process`` time, p50 / p99 / max,
loop closures and ATE. The load average is printed beside them: on a shared machine wall figures include
the neighbours' CPU use.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rbnx.demo.boot import pick_domain_id
from robonix_api.dds import (
    ClockPublisher,
    DdsNode,
    LaserScan,
    OccupancyGrid,
    Odometry,
    StaticTfBroadcaster,
    TfBroadcaster,
)
from robonix_api.dds.convert import laser_scan, odometry
from robonix_api.dds.tf import make_transform
from robonix_api.upstream import Binding
from robonix_eval.slam_loop import SETTINGS, LoopRecording, record_loop
from slam_service.config import parse_config
from slam_service.core import SlamEngine, ate_rmse, kernels
from slam_service.core.numeric import load_in_background
from slam_service.loop import ScanTiming, SlamLoop
from slam_service.provider import ROLES

SCENES = ("apartment", "warehouse")
SKIPS = ("scans_bad_frame", "scans_bad_stamp", "scans_no_tf", "scans_no_odom", "scans_paused", "worker_errors")


def pct(values: list[float]) -> dict[str, float]:
    """p50 / p99 / max in ms of a list of seconds (zeros when empty)."""
    a = 1e3 * np.asarray(values or [0.0])
    return {"p50_ms": float(np.percentile(a, 50)), "p99_ms": float(np.percentile(a, 99)), "max_ms": float(a.max())}


class Hal:
    """What the HAL publishes for SLAM, on its own participant: /clock, /odom, /scan, TF."""

    def __init__(self, node: DdsNode, scan_topic: str, odom_topic: str, rec: LoopRecording) -> None:
        self.clock = ClockPublisher(node)
        self.scan = node.create_publisher(scan_topic, LaserScan, ROLES["scan"][1])
        self.odom = node.create_publisher(odom_topic, Odometry, ROLES["odom"][1])
        self.tf = TfBroadcaster(node)
        self.static = StaticTfBroadcaster(node)
        mount = rec.scans[0].mount
        self.frame = rec.scans[0].frame_id or "laser"
        self.static.send_transform(make_transform("base_link", self.frame, *map(float, mount)))

    def send(self, rec: LoopRecording, k: int) -> None:
        s, (x, y, yaw) = rec.scans[k], map(float, rec.odom[k])
        self.clock.publish(s.stamp)
        self.tf.send("odom", "base_link", x, y, yaw, s.stamp)
        self.odom.publish(odometry(x, y, yaw, stamp=s.stamp))
        self.scan.publish(laser_scan(s.ranges, s.angle_min, s.angle_increment, range_min=s.range_min,
                                     range_max=s.range_max, stamp=s.stamp, frame_id=self.frame))


def settled(loop: SlamLoop) -> bool:
    """Every scan the subscription received was processed, dropped or skipped (the worker is idle)."""
    s = loop.stats()
    done = s.get("scans_processed", 0) + s.get("scans_dropped_behind", 0) + sum(s.get(k, 0) for k in SKIPS)
    return done >= s.get("scans_received", 0) and s.get("queue_depth", 0) == 0


def replay(rec: LoopRecording, rate_hz: float, max_scans: int) -> dict[str, Any]:
    """Feed ``rec`` through a real SlamLoop at ``rate_hz`` wall; the figures of that run."""
    cfg, slam_cfg = parse_config({})
    domain = pick_domain_id()
    hal_node, svc_node = DdsNode(domain, "bench_hal"), DdsNode(domain, "bench_slam")
    bindings = {role: Binding(role, f"/{role}", qos) for role, (_, qos) in ROLES.items()}
    timings: list[ScanTiming] = []
    load_in_background()  # as the provider's CMD_INIT does
    loop = SlamLoop(svc_node, bindings, cfg.frames, SlamEngine(slam_cfg),
                    svc_node.create_publisher("/map", OccupancyGrid, "transient_local"),
                    use_sim_time=cfg.use_sim_time, map_period_s=cfg.map_publish_period_s,
                    tf_period_s=cfg.tf_period_s, queue_size=cfg.scan_queue, on_scan_done=timings.append)
    hal = Hal(hal_node, bindings["scan"].topic, bindings["odom"].topic, rec)
    n = len(rec.scans) if max_scans <= 0 else min(max_scans, len(rec.scans))
    load0 = os.getloadavg()[0]
    try:
        time.sleep(1.0)  # discovery between the two participants (the HAL is up long before SLAM activates)
        loop.set_integrating(True)
        period, late, drops_at, kernels_at = 1.0 / rate_hz, 0.0, [], -1
        t0 = time.monotonic()
        for k in range(n):
            wait = t0 + k * period - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            else:
                late = max(late, -wait)
            hal.send(rec, k)
            if kernels_at < 0 and kernels.ready():  # numba loads in the background after the first /map
                kernels_at = k
            if loop.counters["scans_dropped_behind"] > len(drops_at):  # when (which scan sent) drops happened
                drops_at.extend([k] * (loop.counters["scans_dropped_behind"] - len(drops_at)))
        wall = time.monotonic() - t0
        deadline = time.monotonic() + 120
        while not settled(loop) and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)  # stragglers still in DDS delivery
        while not settled(loop) and time.monotonic() < deadline:
            time.sleep(0.1)
        with loop.lock:
            eng = loop.engine
            eng.flush()
            stamps = eng.node_stamps()
            traj = eng.trajectory()
            lcs, stats = eng.stats.loop_closures, loop.stats()
    finally:
        loop.close()
        for item in (hal.scan, hal.odom, hal.tf, hal.static, hal.clock):
            item.close()
        svc_node.close()
        hal_node.close()
    sent_stamps = np.array([s.stamp for s in rec.scans[:n]])
    idx = np.abs(sent_stamps[None, :] - np.asarray(stamps)[:, None]).argmin(axis=1) if len(stamps) else []
    return {
        "scene": rec.scene, "setting": rec.setting, "seed": rec.seed, "rate_hz": rate_hz, "sent": n,
        "wall_s": wall, "sender_max_late_ms": 1e3 * late,
        "received": stats.get("scans_received", 0), "processed": stats.get("scans_processed", 0),
        "dropped": stats.get("scans_dropped_behind", 0), "dropped_while_sending_scan": drops_at,
        "kernels_ready_at_scan": kernels_at, "queue_size": stats["queue_size"],
        "queue_high_water": stats["queue_high_water"],
        "skipped": {k: stats[k] for k in SKIPS if stats.get(k)},
        "latency": pct([t.latency_s for t in timings]), "queue_wait": pct([t.wait_s for t in timings]),
        "process": pct([t.process_s for t in timings]),
        "process_cpu": pct([t.process_cpu_s for t in timings]),
        "first_scans_latency_ms": [round(1e3 * t.latency_s, 1) for t in timings[:60]],  # the boot transient
        "over_100ms": sum(t.latency_s > 0.1 for t in timings), "over_250ms": sum(t.latency_s > 0.25 for t in timings),
        "loop_closures": lcs, "nodes": len(traj),
        "ate_m": ate_rmse(traj, rec.gt[idx]) if len(traj) else float("nan"),
        "loadavg_1min": [load0, os.getloadavg()[0]],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--setting", choices=sorted(SETTINGS), default="realistic")
    ap.add_argument("--rate", type=float, default=10.0, help="scans per wall second")
    ap.add_argument("--max-scans", type=int, default=0, help="replay only the first N scans (0: the whole loop)")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "slam_provider_drops.json"))
    args = ap.parse_args()
    rows = []
    for scene in args.scenes:
        t = time.monotonic()
        rec = record_loop(scene, seed=args.seed, setting=SETTINGS[args.setting])
        print(f"{scene}: recorded {len(rec.scans)} scans ({rec.drive.path_length:.0f} m, {rec.drive.sim_time:.0f} s "
              f"sim) in {time.monotonic() - t:.0f} s; replaying at {args.rate:g} Hz ...", flush=True)
        r = replay(rec, args.rate, args.max_scans)
        rows.append(r)
        lat, pro, wq, cpu = r["latency"], r["process"], r["queue_wait"], r["process_cpu"]
        print(f"  sent {r['sent']}, received {r['received']}, processed {r['processed']}, DROPPED {r['dropped']} "
              f"(queue {r['queue_size']}, high-water {r['queue_high_water']}), skipped {r['skipped'] or 0}"
              + (f"; drops while sending scans {r['dropped_while_sending_scan'][:10]}" if r["dropped"] else ""))
        print(f"  latency arrival->pose p50 {lat['p50_ms']:.1f} / p99 {lat['p99_ms']:.1f} / max {lat['max_ms']:.0f} ms"
              f" (> 100 ms: {r['over_100ms']}, > 250 ms: {r['over_250ms']}); process() p50 {pro['p50_ms']:.1f} / "
              f"p99 {pro['p99_ms']:.1f} / max {pro['max_ms']:.0f} ms (CPU time p50 {cpu['p50_ms']:.1f} / p99 "
              f"{cpu['p99_ms']:.1f} / max {cpu['max_ms']:.0f} ms); queue wait max {wq['max_ms']:.0f} ms")
        print(f"  loop closures {r['loop_closures']}, {r['nodes']} nodes, ATE {100 * r['ate_m']:.2f} cm; "
              f"numba kernels ready at scan {r['kernels_ready_at_scan']}; "
              f"sender late by <= {r['sender_max_late_ms']:.0f} ms; load average {r['loadavg_1min'][0]:.1f} -> "
              f"{r['loadavg_1min'][1]:.1f} on {os.cpu_count()} CPUs", flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"bench": "slam_provider_drops", "machine": platform.platform(),
                               "python": platform.python_version(), "rows": rows}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
