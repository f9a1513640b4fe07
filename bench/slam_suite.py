"""SLAM quality on the MuJoCo scenes (apartment, warehouse): the in-process pipeline drives a scripted
loop through the scene's waypoints (navigator on the ground-truth map) while SLAM maps from the sim's
drifting odometry and lidar.

One command: ``python bench/slam_suite.py`` (prints a table, writes bench/results/slam_suite.json).
Figures: scans/s inside SlamEngine.process (wall, all scans incl. motion-gated ones), ATE RMSE with loop
closure on and off, occupied-cell IoU (1-cell tolerance, observed walls, lidar-plane obstacles), loop
closures and optimisation time. Two settings per scene (``--settings``): "realistic" (the sim's realistic
drift, 1 cm lidar) and "hard" (2.5x drift, SLAM sees 120 beams with 2.5 cm noise; robonix_eval.slam_loop
HARD_*), each one drive feeding an LC-on and an LC-off engine the same input.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robonix_eval.slam_loop import run_slam_loops  # noqa: E402

SCENES = ("apartment", "warehouse")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--settings", nargs="*", default=["realistic", "hard"])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "slam_suite.json"))
    args = ap.parse_args()
    rows = []
    for scene, setting in [(sc, st) for sc in args.scenes for st in args.settings]:
        on, off = run_slam_loops(scene, seed=args.seed, hard=setting == "hard")
        opt = on.optimize_times
        rows.append({
            "scene": scene, "setting": setting, "scans": on.scans, "nodes": on.nodes, "scans_per_s": on.scans_per_s,
            "ate_lc_on_m": on.ate_rmse, "ate_lc_off_m": off.ate_rmse, "odom_ate_m": on.odom_ate_rmse,
            "iou_lc_on": on.iou, "iou_lc_off": off.iou, "loop_closures": on.loop_closures,
            "optimize_ms_median": 1e3 * statistics.median(opt) if opt else None,
            "optimize_ms_max": 1e3 * max(opt) if opt else None,
            "route_goals_succeeded": sum(g.succeeded for g in on.goals), "route_goals": len(on.goals),
        })
    print(f"{'scene':<10} {'setting':<9} {'scans/s':>7} {'ATE on':>7} {'ATE off':>7} {'odom':>6} {'IoU on':>6} {'IoU off':>7} "
          f"{'LCs':>3} {'opt ms':>6} {'route':>5}")
    for r in rows:
        opt = r["optimize_ms_median"]
        print(f"{r['scene']:<10} {r['setting']:<9} {r['scans_per_s']:>7.0f} {r['ate_lc_on_m']:>7.3f} {r['ate_lc_off_m']:>7.3f} "
              f"{r['odom_ate_m']:>6.2f} {r['iou_lc_on']:>6.3f} {r['iou_lc_off']:>7.3f} {r['loop_closures']:>3} "
              f"{(opt if opt is not None else float('nan')):>6.1f} {r['route_goals_succeeded']}/{r['route_goals']}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"bench": "slam_suite", "seed": args.seed, "machine": platform.machine(),
                               "python": platform.python_version(), "scenes": rows}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
