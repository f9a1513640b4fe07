"""Navigation quality suite: sim + SLAM + navigation cores in one process, unknown map, per scene.

One command: ``python bench/nav_suite.py`` (prints a table, writes bench/results/nav_suite.json).
Per scene: 10 seeded random reachable goals driven in sequence (the SLAM map grows as the robot goes);
success rate, collision events, time and driven path vs the shortest feasible path on the ground-truth
grid, median planning time. Everything but the planning time is sim-time and deterministic per seed.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robonix_eval.goals import sample_goals  # noqa: E402
from robonix_eval.pipeline import Pipeline, PipelineOptions  # noqa: E402

SCENES = ("apartment", "office", "warehouse", "kitchen")


def run_scene(scene: str, n: int, seed: int) -> dict:
    pipe = Pipeline(PipelineOptions(scene=scene, seed=seed))
    goals = sample_goals(pipe.sim, n, seed=seed)
    t0 = time.perf_counter()
    results = pipe.run_goals(goals)
    wall = time.perf_counter() - t0
    ok = [r for r in results if r.succeeded]
    ratios = [r.path_ratio for r in ok if math.isfinite(r.path_ratio)]
    plans = [t for r in results for t in r.plan_times]
    return {
        "scene": scene, "goals": n, "succeeded": len(ok), "success_rate": len(ok) / n,
        "collisions": sum(r.collisions for r in results),
        "within_tolerance": sum(r.within_tolerance for r in ok),
        "time_s_median": statistics.median(r.time for r in ok) if ok else math.nan,
        "time_s_total": sum(r.time for r in results),
        "path_ratio_median": statistics.median(ratios) if ratios else math.nan,
        "path_ratio_max": max(ratios) if ratios else math.nan,
        "plan_ms_median": 1e3 * statistics.median(plans) if plans else math.nan,
        "recoveries": sum(r.recoveries for r in results),
        "sim_s": pipe.time, "wall_s": wall, "real_time_factor": pipe.time / wall,
        "results": [r.to_dict() for r in results],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--goals", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "nav_suite.json"))
    args = ap.parse_args()
    rows = [run_scene(s, args.goals, args.seed) for s in args.scenes]
    n = sum(r["goals"] for r in rows)
    overall = {"goals": n, "succeeded": sum(r["succeeded"] for r in rows),
               "success_rate": sum(r["succeeded"] for r in rows) / n,
               "collisions": sum(r["collisions"] for r in rows),
               "path_ratio_median": statistics.median(
                   x["path_ratio"] for r in rows for x in r["results"]
                   if x["state"] == "SUCCEEDED" and math.isfinite(x["path_ratio"])),
               "plan_ms_median": statistics.median(r["plan_ms_median"] for r in rows)}
    print(f"{'scene':<10} {'succ':>6} {'coll':>4} {'in tol':>6} {'t med s':>7} {'path/short':>10} "
          f"{'max':>5} {'plan ms':>7} {'rec':>3} {'x RT':>5}")
    for r in rows:
        print(f"{r['scene']:<10} {r['succeeded']:>3}/{r['goals']:<2} {r['collisions']:>4} {r['within_tolerance']:>6} "
              f"{r['time_s_median']:>7.1f} {r['path_ratio_median']:>10.2f} {r['path_ratio_max']:>5.2f} "
              f"{r['plan_ms_median']:>7.1f} {r['recoveries']:>3} {r['real_time_factor']:>5.1f}")
    print(f"{'overall':<10} {overall['succeeded']:>3}/{n:<2} {overall['collisions']:>4} {'':>6} {'':>7} "
          f"{overall['path_ratio_median']:>10.2f} {'':>5} {overall['plan_ms_median']:>7.1f}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"bench": "nav_suite", "seed": args.seed, "machine": platform.machine(),
                               "python": platform.python_version(), "overall": overall, "scenes": rows},
                              indent=2, default=float))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
