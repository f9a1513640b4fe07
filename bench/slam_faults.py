"""SLAM fault scenarios in the MuJoCo apartment: data gap during a fast turn, odometry heading jumps, shuffled
stamps, 180° / 30 m, 270° / 0.25° / 80 m and 360° / 1° / 30 m scanners; scored by ATE and map IoU against ground truth.

One command: ``python bench/slam_faults.py`` (prints a table, writes bench/results/slam_faults.json).
Each scenario also runs with ``drop_odom_jumps=True`` (the old jump guard that drops a large step's scan
and its motion) for comparison. Targets: ATE <= 5 cm and IoU >= 0.9 in every scenario.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from dataclasses import asdict
from pathlib import Path

from robonix_eval.slam_faults import (
    ATE_TARGET,
    IOU_TARGET,
    NARROW_FOV_CONFIG,
    SCANNER_DRIVES,
    SCENARIOS,
    SHORT_TOUR,
    TOUR,
    record,
    run_scenario,
)
from slam_service.core import SlamConfig


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="sim seeds (odometry/lidar noise, shuffle delays)")
    ap.add_argument("--short", action="store_true", help="the short tour (half-turn only), for a quick check")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "slam_faults.json"))
    args = ap.parse_args()
    if args.seeds < 1:
        print("slam_faults: --seeds must be >= 1", file=sys.stderr)
        return 2
    route = SHORT_TOUR if args.short else TOUR
    rows = []
    t0 = time.perf_counter()
    for seed in range(args.seeds):
        base_rec = record(route, seed=seed)
        for sc in SCENARIOS:
            rec = record(route, seed=seed, lidar=SCANNER_DRIVES[sc]) if sc in SCANNER_DRIVES else base_rec
            new = run_scenario(rec, sc, seed=seed)
            base = NARROW_FOV_CONFIG if sc == "scanner_180" else SlamConfig(max_range=30.0) \
                if sc in SCANNER_DRIVES else SlamConfig()
            old_cfg = SlamConfig.from_dict({**base.to_dict(), "drop_odom_jumps": True, "reorder_window_s": 0.0})
            old = run_scenario(rec, sc, seed=seed, config=old_cfg)
            rows.append({"seed": seed, "scenario": sc, "note": new.note, "drive_completed": rec.reached,
                         "new": {**asdict(new), "passed": new.passed},
                         "old_behaviour": {**asdict(old), "passed": old.passed}})
            print(f"seed {seed} {sc:14s} new: ATE {new.ate * 100:6.2f} cm IoU {new.iou:.3f} "
                  f"{'PASS' if new.passed else 'FAIL'} | old: ATE {old.ate * 100:7.2f} cm IoU {old.iou:.3f} "
                  f"{'PASS' if old.passed else 'FAIL'}   ({new.note})", flush=True)
    worst = {sc: {"ate_m": max(r["new"]["ate"] for r in rows if r["scenario"] == sc),
                  "iou": min(r["new"]["iou"] for r in rows if r["scenario"] == sc)} for sc in SCENARIOS}
    ok = all(r["new"]["passed"] for r in rows)
    print(f"\nworst over {args.seeds} seeds (targets ATE <= {ATE_TARGET * 100:.0f} cm, IoU >= {IOU_TARGET}):")
    for sc, w in worst.items():
        print(f"  {sc:14s} ATE {w['ate_m'] * 100:5.2f} cm  IoU {w['iou']:.3f}")
    print(f"all scenarios pass: {ok}   ({time.perf_counter() - t0:.0f} s)")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"machine": platform.platform(), "route": "short" if args.short else "tour",
                               "targets": {"ate_m": ATE_TARGET, "iou": IOU_TARGET}, "worst": worst,
                               "all_pass": ok, "runs": rows}, indent=2, default=float))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
