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
import math
import sys
import time
import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np

from hal_panda_mobile.files import load_robot_description, load_scene
from hal_panda_mobile.sim import PandaMobileSim
from robonix_eval.slam_loop import LOOPS, REALISTIC, ScriptedDriver
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse, occupied_iou

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "bench" / "results" / "slam_lifelong.json"


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
    robot = load_robot_description()
    st = REALISTIC
    sim = PandaMobileSim(robot, load_scene("apartment"), seed=seed, odom_noise=st.odom_noise,
                         lidar_noise=st.lidar_noise)
    cfg = SlamConfig()
    if not prune and hasattr(cfg, "prune_nodes"):
        cfg = SlamConfig.from_dict({**cfg.to_dict(), "prune_nodes": False})
    eng = SlamEngine(cfg)
    mx, my, _, myaw = robot.lidar.mount
    x0, y0, *_ = sim.ground_truth()
    route = list(LOOPS["apartment"])
    ctrl_every = max(1, round(0.05 / sim.timestep))
    scan_every = max(1, round(0.1 / sim.timestep))
    gt_at: dict[float, tuple[float, float, float]] = {}
    rows, lat = [], []
    driven, last = 0.0, (x0, y0)
    tracemalloc.start()
    t0 = time.perf_counter()
    for lap in range(1, laps + 1):
        driver = ScriptedDriver(last, route, speed)
        step, lat = 0, []
        while not driver.done:
            sim.step(ctrl_every)
            step += ctrl_every
            x, y, yaw, *_ = sim.ground_truth()
            driven += math.hypot(x - last[0], y - last[1])
            last = (x, y)
            if step % scan_every == 0:
                s, o = sim.scan(), sim.odometry()
                gt_at[round(s.stamp, 6)] = (x, y, yaw)
                scan = Scan(np.asarray(s.ranges, dtype=np.float32), s.angle_min, s.angle_increment, s.range_min,
                            s.range_max, s.stamp, (mx, my, myaw), s.frame_id)
                t1 = time.perf_counter()
                eng.process(scan, (o.x, o.y, o.yaw), s.stamp)
                lat.append(time.perf_counter() - t1)
            sim.set_cmd_vel(*driver.command(x, y, yaw), stamp=sim.time)
        row = lap_row(eng, lap, driven, lat, time.perf_counter() - t0)
        gt = np.array([gt_at[round(float(t), 6)] for t in eng.node_stamps()]).reshape(-1, 3)
        err = np.hypot(*(eng.trajectory()[:, :2] - gt[:, :2]).T)
        row["ate_m"], row["max_err_m"] = round(ate_rmse(eng.trajectory(), gt), 4), round(float(err.max()), 3)
        rows.append(row)
        print(json.dumps(row), flush=True)
    sim.stop()
    eng.flush()
    tracemalloc.stop()
    stamps = [round(float(t), 6) for t in eng.node_stamps()]
    gt = np.array([gt_at[t] for t in stamps]).reshape(-1, 3)
    truth = sim.ground_truth_grid(cfg.resolution, min_height=robot.lidar.mount[2])
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
