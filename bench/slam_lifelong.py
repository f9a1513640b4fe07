"""SLAM memory vs distance driven, in-process: the MuJoCo apartment's scripted loop driven lap after lap.

Why: the sim-deploy soak showed the mapping provider's memory growing while the robot only revisited
mapped rooms. This drives the same kind of revisiting trajectory straight into one ``SlamEngine`` (no
processes, fast) and prints, per lap, what each per-node structure holds (node scans, no-return ends,
graph edges, the grid), the Python heap (tracemalloc) and the per-scan latency p99, so a structure that
grows with distance rather than area shows up in a few laps.

    python bench/slam_lifelong.py [--laps 6] [--speed 0.8] [--no-prune]

Writes bench/results/slam_lifelong.json.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tracemalloc
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from robonix_eval.slam_loop import LOOPS, REALISTIC, drive_loop
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse, occupied_iou

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "bench" / "results" / "slam_lifelong.json"
LEG_TIMEOUT_S = 40.0  # a leg not finished in this sim time means the drive is stuck: stop there


def structure_bytes(eng: SlamEngine) -> dict[str, int]:
    """Array payload bytes per engine structure (what should be bounded by the mapped area)."""
    g = eng.graph
    return {
        "node_points": int(sum(p.nbytes for p in eng._points)),
        "no_return_ends": int(sum(p.nbytes for p in eng._free.values())),
        "graph_poses": int(g.poses.nbytes),
        "graph_edges": int(sum(z.nbytes for z in g.edge_z) + sum(i.nbytes for i in g.edge_info)),
        "grid": int(eng.grid.logodds.nbytes),
    }


def lap_row(eng: SlamEngine, lap: int, driven: float, lat: list[float], t_wall: float) -> dict[str, Any]:
    cur, _peak = tracemalloc.get_traced_memory()
    return {"lap": lap, "driven_m": round(driven, 1), "nodes": eng.graph.n_nodes, "edges": eng.graph.n_edges,
            "loop_closures": eng.stats.loop_closures, "pruned": getattr(eng.stats, "nodes_pruned", 0),
            "heap_mb": round(cur / 1e6, 2), "bytes": structure_bytes(eng),
            "p50_ms": round(1e3 * float(np.percentile(lat, 50)), 2),
            "p99_ms": round(1e3 * float(np.percentile(lat, 99)), 2), "wall_s": round(t_wall, 1)}


def run(laps: int, speed: float, prune: bool, seed: int) -> dict[str, Any]:
    cfg = SlamConfig()
    if not prune and hasattr(cfg, "prune_nodes"):
        cfg = SlamConfig.from_dict({**cfg.to_dict(), "prune_nodes": False})
    # The shared evaluation drive (robonix_eval.slam_loop.drive_loop), full 360-beam realistic lidar, driving
    # the apartment loop ``laps`` times in a row; a lap ends each time the route's last waypoint is reached.
    st = replace(REALISTIC, speed=speed, beam_step=1, max_range=None, slam_config=cfg)
    eng = SlamEngine(cfg)
    route = list(LOOPS["apartment"])
    gt_at: dict[float, tuple[float, float, float]] = {}
    rows: list[dict[str, Any]] = []
    lat: list[float] = []
    t0 = time.perf_counter()

    def feed(scan: Scan, odom: tuple[float, float, float], gt: tuple[float, float, float], _wz: float) -> None:
        if not tracemalloc.is_tracing():  # the heap figure is SLAM's, not the sim's set-up
            tracemalloc.start()
        gt_at[round(scan.stamp, 6)] = gt
        t1 = time.perf_counter()
        eng.process(scan, odom, scan.stamp)
        lat.append(time.perf_counter() - t1)

    def lap_done(reached: int, driven: float) -> None:
        if reached % len(route):
            return
        row = lap_row(eng, reached // len(route), driven, lat, time.perf_counter() - t0)
        gt = np.array([gt_at[round(float(t), 6)] for t in eng.node_stamps()]).reshape(-1, 3)
        err = np.hypot(*(eng.trajectory()[:, :2] - gt[:, :2]).T)
        row["ate_m"], row["max_err_m"] = round(ate_rmse(eng.trajectory(), gt), 4), round(float(err.max()), 3)
        rows.append(row)
        print(json.dumps(row), flush=True)
        lat.clear()

    drive, truth = drive_loop("apartment", st, seed, route * laps, LEG_TIMEOUT_S, feed, lap_done)
    eng.flush()
    tracemalloc.stop()
    if not drive.completed:
        print(f"drive stopped early: {drive.reached}/{drive.waypoints} waypoints", flush=True)
    stamps = [round(float(t), 6) for t in eng.node_stamps()]
    gt = np.array([gt_at[t] for t in stamps]).reshape(-1, 3)
    final = {"ate_m": round(ate_rmse(eng.trajectory(), gt), 4),
             "iou": round(occupied_iou(eng.map(), truth, tolerance_cells=1, observed_only=True), 4)}
    print(json.dumps(final), flush=True)
    return {"laps": rows, "final": final, "prune": prune, "speed": speed, "seed": seed}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--laps", type=int, default=6)
    ap.add_argument("--speed", type=float, default=0.8, help="m/s along each leg")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-prune", action="store_true", help="lifelong node pruning off (the old behaviour)")
    args = ap.parse_args()
    res = run(args.laps, args.speed, not args.no_prune, args.seed)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(res, indent=2) + "\n")
    print(f"-> {RESULTS.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
