"""SLAM quality on the MuJoCo scenes (apartment, warehouse): a scripted loop (robonix_eval.slam_loop.LOOPS,
holonomic P-controller on the true pose, no navigation stack) while SLAM maps from the sim's drifting
odometry and lidar.

One command: ``python bench/slam_suite.py`` (prints a per-seed table, writes bench/results/slam_suite.json).
Figures: scans/s inside SlamEngine.process (wall, all scans incl. motion-gated ones), per-call latency
(p50 / p99 / max wall ms of the LC-on engine, calls over 100 / 250 ms), ATE RMSE with loop
closure on and off, occupied-cell IoU (1-cell tolerance, observed walls, lidar-plane obstacles), loop
closures, optimisation time, drive collisions. Two settings per scene (``--settings``): "realistic" (the
sim's realistic drift, 360 beams, 1 cm) and "hard" (2.5x drift; SLAM sees 120 beams, 2.5 cm noise, 3 %
dropouts; robonix_eval.slam_loop.HARD), each one drive feeding an LC-on and an LC-off engine the same input.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robonix_eval.slam_loop import run_slam_loops
from slam_service.core import kernels
from slam_service.core.numeric import load_numeric_stack

SCENES = ("apartment", "warehouse")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2])
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--settings", nargs="*", default=["realistic", "hard"])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "slam_suite.json"))
    args = ap.parse_args()
    rows = []
    load_numeric_stack()  # as the provider does at CMD_INIT: the first scan does not pay for importing scipy
    kernels.load()  # and after its first map: the numba kernels (their numpy twins give identical results)
    print(f"{'scene':<10} {'setting':<9} {'seed':>4} {'scans/s':>7} {'ATE on':>7} {'ATE off':>7} {'off-on':>7} "
          f"{'odom':>6} {'IoU on':>6} {'IoU off':>7} {'LCs':>3} {'opt ms':>6} {'route':>5} {'coll':>4} "
          f"{'p50 ms':>6} {'p99 ms':>6} {'max ms':>6} {'>100':>4} {'>250':>4}")
    for scene, setting, seed in [(sc, st, sd) for sc in args.scenes for st in args.settings for sd in args.seeds]:
        on, off = run_slam_loops(scene, seed=seed, hard=setting == "hard")
        opt = on.optimize_times
        lat = 1e3 * np.asarray(on.latencies)  # every process() call of the LC-on engine, wall ms
        r = {
            "scene": scene, "setting": setting, "seed": seed, "scans": on.scans, "nodes": on.nodes,
            "scans_per_s": on.scans_per_s, "ate_lc_on_m": on.ate_rmse, "ate_lc_off_m": off.ate_rmse,
            "odom_ate_m": on.odom_ate_rmse, "iou_lc_on": on.iou, "iou_lc_off": off.iou,
            "loop_closures": on.loop_closures,
            "optimize_ms_median": 1e3 * statistics.median(opt) if opt else None,
            "optimize_ms_max": 1e3 * max(opt) if opt else None,
            "waypoints_reached": on.drive.reached, "waypoints": on.drive.waypoints,
            "collisions": on.drive.collisions, "path_m": on.drive.path_length, "sim_s": on.drive.sim_time,
            "latency_p50_ms": float(np.percentile(lat, 50)), "latency_p99_ms": float(np.percentile(lat, 99)),
            "latency_max_ms": float(lat.max()), "latency_over_100ms": int((lat > 100).sum()),
            "latency_over_250ms": int((lat > 250).sum()),
        }
        rows.append(r)
        o = r["optimize_ms_median"]
        print(f"{scene:<10} {setting:<9} {seed:>4} {r['scans_per_s']:>7.0f} {on.ate_rmse:>7.3f} {off.ate_rmse:>7.3f} "
              f"{off.ate_rmse - on.ate_rmse:>+7.3f} {on.odom_ate_rmse:>6.2f} {on.iou:>6.3f} {off.iou:>7.3f} "
              f"{on.loop_closures:>3} {(o if o is not None else float('nan')):>6.1f} "
              f"{on.drive.reached:>2}/{on.drive.waypoints:<2} {on.drive.collisions:>4} "
              f"{r['latency_p50_ms']:>6.1f} {r['latency_p99_ms']:>6.1f} {r['latency_max_ms']:>6.0f} "
              f"{r['latency_over_100ms']:>4} {r['latency_over_250ms']:>4}", flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"bench": "slam_suite", "seeds": args.seeds, "machine": platform.machine(),
                               "python": platform.python_version(), "rows": rows}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
