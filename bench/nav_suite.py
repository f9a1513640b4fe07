"""Navigation quality suite: sim + SLAM + navigation cores in one process, unknown map, per scene.

One command: ``python bench/nav_suite.py`` (prints a table, writes bench/results/nav_suite.json).
Per scene: 10 seeded random reachable goals driven in sequence (the SLAM map grows as the robot goes);
success rate, collision events, time and driven path vs the shortest feasible path on the ground-truth
grid, median planning time. Everything but the planning time is sim-time and deterministic per seed.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hal_panda_mobile.sim import LidarNoise
from robonix_eval.goals import sample_goals
from robonix_eval.pipeline import GoalResult, Pipeline, PipelineOptions
from robonix_eval.slam_loop import ROUTES

SCENES = ("apartment", "office", "warehouse", "kitchen")


def run_scene(scene: str, n: int, seed: int, lidar: LidarNoise | None = None, controller: str = "profile") -> dict:
    opts = PipelineOptions(scene=scene, seed=seed, controller=controller)
    if lidar is not None:
        opts = PipelineOptions(scene=scene, seed=seed, lidar_noise=lidar, controller=controller)
    pipe = Pipeline(opts)
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
        "closest_m_min": min((r.closest_m for r in results), default=math.nan),
        "sim_s": pipe.time, "wall_s": wall, "real_time_factor": pipe.time / wall,
        "results": [r.to_dict() for r in results],
    }


def run_hard(seed: int) -> list[dict]:
    """The scenarios that used to fail: the apartment route (narrow doorways) on the ground-truth map with
    2–3 cm lidar noise and dropouts, and a 0.8 m gap beside a box dropped 1.5 m ahead in the office corridor."""
    out = []
    for std, drop in ((0.02, 0.02), (0.03, 0.05)):
        pipe = Pipeline(PipelineOptions(scene="apartment", seed=seed, nav_map="ground_truth",
                                        lidar_noise=LidarNoise(noise_std=std, dropout_prob=drop)))
        wps = pipe.sim.scene.waypoints
        res = pipe.run_goals([(float(wps[n][0]), float(wps[n][1]), 0.0) for n in ROUTES["apartment"]])
        out.append(_hard_row(f"apartment route, noise {std} m / dropout {drop}", res))
    for side, y, std in (("south", 5.6, 0.01), ("north", 6.4, 0.03)):
        pipe = Pipeline(PipelineOptions(scene="office", seed=seed,
                                        lidar_noise=LidarNoise(noise_std=std, dropout_prob=0.02)))
        box, dropped = (8.0, y, 0.6, 1.1), []

        def drop_box(p: Pipeline, box: tuple = box, dropped: list = dropped) -> None:
            if not dropped and p.ground_truth_pose()[0] > box[0] - 1.5:
                p.sim.spawn_box("dropped", *box)
                dropped.append(p.time)

        pipe.hooks.append(drop_box)
        out.append(_hard_row(f"0.8 m gap ({side} box), noise {std} m", pipe.run_goals([(14.5, 6.0, 0.0)])))
    print(f"{'hard scenario':<44} {'succ':>5} {'coll':>4} {'rec':>3} {'closest cm':>10}")
    for r in out:
        print(f"{r['scenario']:<44} {r['succeeded']:>2}/{r['goals']:<2} {r['collisions']:>4} {r['recoveries']:>3} "
              f"{100 * r['closest_m_min']:>10.1f}")
    return out


def _hard_row(name: str, res: list[GoalResult]) -> dict:
    return {"scenario": name, "goals": len(res), "succeeded": sum(r.succeeded for r in res),
            "collisions": sum(r.collisions for r in res), "recoveries": sum(r.recoveries for r in res),
            "closest_m_min": min((r.closest_m for r in res), default=math.nan),
            "results": [r.to_dict() for r in res]}


def _table(rows: list[dict]) -> dict:
    """Print one pass's per-scene table and return its overall figures with the rows."""
    n = sum(r["goals"] for r in rows)
    overall = {"goals": n, "succeeded": sum(r["succeeded"] for r in rows),
               "success_rate": sum(r["succeeded"] for r in rows) / n,
               "collisions": sum(r["collisions"] for r in rows),
               "recoveries": sum(r["recoveries"] for r in rows),
               "path_ratio_median": statistics.median(
                   [x["path_ratio"] for r in rows for x in r["results"]
                    if x["succeeded"] and math.isfinite(x["path_ratio"])] or [math.nan]),
               "plan_ms_median": statistics.median(r["plan_ms_median"] for r in rows),
               "closest_m_min": min(r["closest_m_min"] for r in rows)}
    print(f"{'scene':<10} {'succ':>6} {'coll':>4} {'in tol':>6} {'t med s':>7} {'path/short':>10} "
          f"{'max':>5} {'plan ms':>7} {'rec':>3} {'x RT':>5} {'closest cm':>10}")
    for r in rows:
        print(f"{r['scene']:<10} {r['succeeded']:>3}/{r['goals']:<2} {r['collisions']:>4} {r['within_tolerance']:>6} "
              f"{r['time_s_median']:>7.1f} {r['path_ratio_median']:>10.2f} {r['path_ratio_max']:>5.2f} "
              f"{r['plan_ms_median']:>7.1f} {r['recoveries']:>3} {r['real_time_factor']:>5.1f} "
              f"{100 * r['closest_m_min']:>10.1f}")
    print(f"{'overall':<10} {overall['succeeded']:>3}/{n:<2} {overall['collisions']:>4} {'':>6} {'':>7} "
          f"{overall['path_ratio_median']:>10.2f} {'':>5} {overall['plan_ms_median']:>7.1f} "
          f"{overall['recoveries']:>3} {'':>5} {100 * overall['closest_m_min']:>10.1f}")
    return {"overall": overall, "scenes": rows}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--goals", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "nav_suite.json"))
    ap.add_argument("--lidar-noise", nargs=2, type=float, metavar=("STD_M", "DROPOUT"), default=None,
                    help="also run a second pass with this lidar range noise (m) and dropout probability, "
                         "e.g. 0.03 0.05")
    ap.add_argument("--no-hard", action="store_true", help="skip the hard scenarios (noisy route, 0.8 m gap)")
    ap.add_argument("--controller", choices=("profile", "pursuit", "mppi"), default="profile",
                    help="the sim profile's controller plugin, or override it")
    args = ap.parse_args()
    passes = {"nominal": None}
    if args.lidar_noise:
        passes["noisy"] = LidarNoise(noise_std=args.lidar_noise[0], dropout_prob=args.lidar_noise[1])
    report = {}
    for label, lidar in passes.items():
        rows = [run_scene(s, args.goals, args.seed, lidar, args.controller) for s in args.scenes]
        print(f"== {label}" + (f": lidar noise {lidar.noise_std} m, dropout {lidar.dropout_prob}" if lidar else ""))
        report[label] = {"lidar_noise": dataclasses.asdict(lidar) if lidar else None, **_table(rows)}
    hard = [] if args.no_hard else run_hard(args.seed)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    nominal = report["nominal"]
    out.write_text(json.dumps({"bench": "nav_suite", "seed": args.seed, "machine": platform.machine(),
                               "python": platform.python_version(), "controller": args.controller,
                               "overall": nominal["overall"],
                               "scenes": nominal["scenes"], "passes": report,
                               "hard": hard}, indent=2, default=float))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
