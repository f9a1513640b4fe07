"""Navigation in clutter: generated post fields, each proven passable, crossed by the in-process stack.

    python bench/clutter_suite.py [--worlds 200] [--seeds 3] [--noise both|on|off] [--controller pursuit|mppi]
                                  [--only 41,74,94] [--se2 on|off] [--jobs 2] [--out bench/results/clutter_suite.json]

``--only`` drives just the worlds of the listed generator seeds (the number in a world's name, ``clutter_41``),
e.g. to rerun the failures of a full run without generating and proving all the worlds before them.

The full suite is ~1200 crossings (hours of CPU), so every finished crossing is appended at once to
``<out>.rows.jsonl``; ``--resume`` reuses the crossings already there (same world, seed, noise and the same
settings) and runs only the rest, so an interrupted run loses at most the crossings in flight.

Worlds come from :mod:`robonix_eval.clutter` (cellular automaton on a 0.15 m grid, fill drawn uniformly
from 10–35 %, two smoothing passes; walls on three sides; start 1 m above the south wall, goal 10 m above
the start). A world is used only when the configuration-space proof shows that the 0.70 × 0.50 m
rectangle grown by ``--margin`` can rotate and translate from start to goal; the rejected draws are
counted. Each kept world is driven once per seed and noise setting by the sim + SLAM + navigation cores
in one process (unknown map: navigation plans on the SLAM map as it grows).

A run succeeds only if the goal SUCCEEDED **and** the base touched nothing on the way (a contact is a
failure). Time is compared with the shortest path's length at the controller's cruise speed; that length
is a lower bound (the centre's shortest route through cells free at some heading), so the ratio is
pessimistic.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from robonix_eval.clutter import ClutterWorld, generate

FILL = (0.10, 0.35)


def make_worlds(n: int, margin: float, first_seed: int = 0) -> tuple[list[ClutterWorld], int]:
    """The first ``n`` passable worlds from consecutive seeds, and how many draws were rejected."""
    worlds, rejected, seed = [], 0, first_seed
    while len(worlds) < n:
        fill = float(np.random.default_rng(seed + 7_000_000).uniform(*FILL))
        w = generate(seed, fill, margin=margin, survive=3)
        if w.passable:
            worlds.append(w)
        else:
            rejected += 1
        seed += 1
        if seed - first_seed > 50 * n + 100:
            raise SystemExit(f"clutter_suite: only {len(worlds)} passable worlds in {seed - first_seed} draws")
    return worlds, rejected


def make_selected(seeds: list[int], margin: float) -> list[ClutterWorld]:
    """The worlds of the given generator seeds (as ``make_worlds`` draws them); a seed whose draw the proof
    rejects is an error, since ``make_worlds`` never uses it."""
    worlds = []
    for seed in seeds:
        fill = float(np.random.default_rng(seed + 7_000_000).uniform(*FILL))
        w = generate(seed, fill, margin=margin, survive=3)
        if not w.passable:
            raise SystemExit(f"clutter_suite: the draw of seed {seed} is not passable (make_worlds skips it)")
        worlds.append(w)
    return worlds


def run_one(job: tuple[dict, int, float, float, bool, str, float, bool]) -> dict:
    """One crossing; runs in a worker process (everything it needs travels in ``job``)."""
    from hal_panda_mobile.sim import LidarNoise, OdomNoise
    from robonix_eval.pipeline import Pipeline, PipelineOptions

    scene, seed, shortest, fill, noisy, controller, timeout, se2 = job
    if noisy:
        opts = PipelineOptions(scene=scene, seed=seed, controller=controller)
    else:
        opts = PipelineOptions(scene=scene, seed=seed, controller=controller, odom_noise=OdomNoise(),
                               lidar_noise=LidarNoise())
    t0 = time.perf_counter()
    pipe = Pipeline(opts)
    pipe.nav.cfg.planner.se2.enabled = se2
    pipe.run_for(0.5)
    gx, gy = scene["waypoints"]["goal"]
    res = pipe.navigate(gx, gy, math.pi / 2, timeout=timeout)
    cruise = pipe.params.config.controller.desired_linear_vel
    return {"world": scene["name"], "fill": fill, "seed": seed, "noise": noisy, "state": res.state,
            "detail": res.detail, "collisions": res.collisions, "recoveries": res.recoveries,
            "success": res.succeeded and res.collisions == 0, "time": res.time,
            "shortest_lower_bound": shortest, "time_ratio": res.time / (shortest / cruise),
            "wall_s": time.perf_counter() - t0, **pipe.nav.footprint_planner.stats.summary(),
            "se2_seconds": pipe.nav.footprint_planner.stats.seconds}


def _key(world: str, seed: int, noisy: bool) -> str:
    return f"{world}/{seed}/{'noise' if noisy else 'clean'}"


def load_done(rows_path: Path, settings: dict, resume: bool) -> dict[str, dict]:
    """The crossings a previous run of the same settings finished (``--resume``); else start the file anew."""
    if resume and rows_path.exists():
        lines = [json.loads(line) for line in rows_path.read_text().splitlines() if line.strip()]
        if not lines or lines[0].get("settings") != settings:
            raise SystemExit(f"clutter_suite: {rows_path} was written with other settings "
                             f"({lines[0].get('settings') if lines else 'empty'}); drop --resume or pick another --out")
        return {_key(r["world"], r["seed"], r["noise"]): r for r in lines[1:]}
    rows_path.parent.mkdir(parents=True, exist_ok=True)
    rows_path.write_text(json.dumps({"settings": settings}) + "\n")
    return {}


def _seeds(text: str) -> list[int]:
    """``--only``'s world seeds (empty: all of ``--worlds``)."""
    try:
        out = [int(v) for v in text.split(",") if v.strip()]
    except ValueError as exc:
        raise SystemExit(f"clutter_suite: --only takes comma-separated seeds, got {text!r}") from exc
    if any(i < 0 or i >= 1_000_000 for i in out):
        raise SystemExit("clutter_suite: --only seeds must be 0..999999")
    return out


def se2_summary(rows: list[dict]) -> dict:
    """Planning time the SE(2) fallback added, over every run of it in every crossing."""
    secs = [s for r in rows for s in r.get("se2_seconds", [])]
    return {"runs": len(secs), "crossings_using_it": sum(r.get("se2_runs", 0) > 0 for r in rows),
            "reuses": sum(r.get("se2_reuses", 0) for r in rows),
            "reheaded": sum(r.get("se2_reheaded", 0) for r in rows),
            "slice_max_s": max((r.get("se2_slice_max_s", 0.0) for r in rows), default=0.0),
            "median_s": statistics.median(secs) if secs else 0.0, "max_s": max(secs) if secs else 0.0}


def summarise(rows: list[dict]) -> dict:
    def block(sel: list[dict]) -> dict:
        ok = [r for r in sel if r["success"]]
        return {"runs": len(sel), "succeeded": len(ok), "success_rate": len(ok) / len(sel) if sel else math.nan,
                "collisions": sum(r["collisions"] for r in sel),
                "runs_with_contact": sum(r["collisions"] > 0 for r in sel),
                "time_ratio_median": statistics.median(r["time_ratio"] for r in ok) if ok else math.nan}

    out = {"all": block(rows)}
    for noisy in (True, False):
        sel = [r for r in rows if r["noise"] == noisy]
        if sel:
            out["noise" if noisy else "no_noise"] = block(sel)
    for lo, hi in ((0.10, 0.20), (0.20, 0.28), (0.28, 0.36)):
        sel = [r for r in rows if lo <= r["fill"] < hi]
        if sel:
            out[f"fill_{lo:.2f}-{hi:.2f}"] = block(sel)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--worlds", type=int, default=200)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--noise", choices=("both", "on", "off"), default="both")
    ap.add_argument("--controller", choices=("profile", "pursuit", "mppi"), default="profile",
                    help="the sim profile's controller, or override it")
    ap.add_argument("--margin", type=float, default=0.05, help="m of clearance the passability proof demands")
    ap.add_argument("--timeout", type=float, default=120.0, help="s of sim time per crossing")
    ap.add_argument("--only", default="", help="comma-separated generator seeds of the worlds to run (clutter_<seed>)")
    ap.add_argument("--se2", choices=("on", "off"), default="on",
                    help="the planner's footprint-aware SE(2) fallback (off: the 2D plan only, for comparison)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "clutter_suite.json"))
    ap.add_argument("--resume", action="store_true",
                    help="reuse the crossings <out>.rows.jsonl already holds (same settings); run the rest")
    a = ap.parse_args()
    if not (1 <= a.worlds <= 10_000 and 1 <= a.seeds <= 100 and 1 <= a.jobs <= 64 and 0 <= a.margin <= 0.5):
        raise SystemExit("clutter_suite: --worlds 1..10000, --seeds 1..100, --jobs 1..64, --margin 0..0.5")
    only = _seeds(a.only)
    t0 = time.perf_counter()
    worlds, rejected = (make_selected(only, a.margin), 0) if only else make_worlds(a.worlds, a.margin)
    print(f"{len(worlds)} passable worlds ({rejected} draws rejected by the proof) in {time.perf_counter() - t0:.0f} s",
          flush=True)
    noises = {"both": (True, False), "on": (True,), "off": (False,)}[a.noise]
    rows_path = Path(a.out).with_suffix(".rows.jsonl")
    done = load_done(rows_path, {"controller": a.controller, "margin": a.margin, "timeout": a.timeout,
                                 "se2": a.se2}, a.resume)
    wanted = [(w, s, n) for w in worlds for s in range(a.seeds) for n in noises]
    rows = [done[k] for w, s, n in wanted if (k := _key(f"clutter_{w.seed}", s, n)) in done]
    jobs = [(w.scene(), s, w.shortest, w.fill, n, a.controller, a.timeout, a.se2 == "on")
            for w, s, n in wanted if _key(f"clutter_{w.seed}", s, n) not in done]
    if rows:
        print(f"resumed: {len(rows)} crossings from {rows_path}, {len(jobs)} to run", flush=True)
    with ProcessPoolExecutor(a.jobs, mp_context=get_context("spawn")) as pool, rows_path.open("a") as log:
        for row in pool.map(run_one, jobs):
            rows.append(row)
            log.write(json.dumps(row) + "\n")
            log.flush()
            if not row["success"]:
                print(f"  {row['world']} seed {row['seed']} noise {row['noise']}: {row['state']}, "
                      f"{row['collisions']} contacts: {row['detail'][:80]}", flush=True)
            if len(rows) % 20 == 0:
                ok = sum(r["success"] for r in rows)
                print(f"{len(rows)}/{len(wanted)} runs, {ok} succeeded", flush=True)
    summary = summarise(rows)
    for k, v in summary.items():
        print(f"{k:<16} {v['succeeded']:>4}/{v['runs']:<4} success {v['success_rate']:.3f}  contacts "
              f"{v['collisions']:>3} in {v['runs_with_contact']} runs  time/shortest median "
              f"{v['time_ratio_median']:.2f}")
    se2 = se2_summary(rows)
    print(f"se2 fallback: {se2['runs']} runs in {se2['crossings_using_it']} crossings, median "
          f"{se2['median_s'] * 1000:.0f} ms, max {se2['max_s'] * 1000:.0f} ms; kept its path at {se2['reuses']} "
          f"replans ({se2['reheaded']} with new headings); longest single call (stall) "
          f"{se2['slice_max_s'] * 1000:.0f} ms")
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"args": vars(a), "rejected_draws": rejected, "summary": summary, "se2": se2,
                               "runs": rows, "machine": platform.platform(), "wall_s": time.perf_counter() - t0},
                              indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
