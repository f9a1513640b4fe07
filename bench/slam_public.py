"""SLAM on real robots' public laser logs (Intel Research Lab, ACES, MIT CSAIL; CARMEN format).

One command: ``python bench/slam_public.py`` (prints a table, writes bench/results/slam_public.json and a
map PNG per log under bench/results/slam_public/). Each log's FLASER lines are fed, in file order (what a
replay delivers: bursty, partly out of order), to ``slam_service.core.SlamEngine`` with the default
configuration; after the last scan the engine is flushed and optimised once more.

Figures per log: Kuemmerle et al.'s relation metric (mean +- std of translational (m) and rotational (deg)
error; logs with a ``.relations`` file), CPU time of every ``process()`` call (p50 / p99 / max ms, calls
over 250 ms; ``time.thread_time`` of the calling thread, so it is the scan path's own cost whatever the
machine's load), scans/s, loop closures accepted / rejected, the engine's timestamp counters, and for
every log (MIT CSAIL has no relations) a revisit-consistency figure: wherever the trajectory comes back to
a place it saw more than ``REVISIT_PATH_M`` of path earlier, the two scans are matched directly and the
disagreement with the graph's relative pose is reported (a doubled wall is such a disagreement).

Develop on slices: ``--max-scans 2000``; the full logs take minutes each (run them with ``nice``).
"""

from __future__ import annotations

import argparse
import collections
import json
import logging
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robonix_common.geometry import relative, transform_points
from robonix_eval.carmen import read_carmen, to_scan
from robonix_eval.relations import read_relations, scan_poses, score_relations
from slam_service.core import SlamConfig, SlamEngine, kernels
from slam_service.core.lookup import LookupGrid
from slam_service.core.matcher import inlier_fraction, match_scan, required_margin
from slam_service.core.numeric import load_numeric_stack
from slam_service.render import render_map_png

# the logs live next to the repository (../shared/data/...); a worktree sits one level deeper
DATA = next((p / "shared" / "data" / "real_laser_logs" for p in Path(__file__).resolve().parents[1:4]
             if (p / "shared" / "data" / "real_laser_logs").is_dir()), Path("../shared/data/real_laser_logs"))
LOGS = ("intel", "aces", "mit-csail")
REVISIT_PATH_M = 10.0  # a revisit: within 0.5 m and 0.5 rad of a node at least this much path earlier
REVISIT_SAMPLES = 300  # revisit pairs checked per log (evenly spread), bounds the check's cost


class _RejectReasons(logging.Handler):
    """Counts the engine's "loop closure rejected: <why>" debug lines (why candidates fail, per log)."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.counts: collections.Counter[str] = collections.Counter()

    def emit(self, record: logging.LogRecord) -> None:
        msg = record.getMessage()
        if "loop closure rejected: " in msg:
            self.counts[msg.split("loop closure rejected: ", 1)[1]] += 1


def run_log(name: str, data: Path, max_scans: int | None, config: SlamConfig) -> tuple[dict, SlamEngine]:
    recs = read_carmen(data / f"{name}.clf.bz2", max_scans=max_scans)
    eng = SlamEngine(config)
    reasons = _RejectReasons()
    engine_log = logging.getLogger("slam_service.core.engine")
    engine_log.addHandler(reasons)
    engine_log.setLevel(logging.DEBUG)
    cpu = np.empty(len(recs))
    w0 = time.perf_counter()
    for i, r in enumerate(recs):
        t0 = time.thread_time()
        eng.process(to_scan(r), r.odom, r.stamp)
        cpu[i] = time.thread_time() - t0
    t0 = time.thread_time()
    eng.flush()
    flush_cpu = time.thread_time() - t0
    wall = time.perf_counter() - w0
    engine_log.removeHandler(reasons)
    t0 = time.thread_time()
    eng.optimize()
    final_opt = time.thread_time() - t0
    stamps = np.array([r.stamp for r in recs])
    odom = np.array([r.odom for r in recs])
    poses = scan_poses(eng.node_stamps(), eng.trajectory(), stamps, odom)
    ms = 1e3 * cpu
    s = eng.stats
    row: dict = {
        "log": name, "scans": len(recs), "nodes": eng.graph.n_nodes, "wall_s": wall,
        "scans_per_s": len(recs) / wall, "cpu_ms_p50": float(np.percentile(ms, 50)),
        "cpu_ms_p99": float(np.percentile(ms, 99)), "cpu_ms_max": float(ms.max()),
        "calls_over_250ms": int((ms > 250).sum()), "flush_cpu_ms": 1e3 * flush_cpu,
        "final_optimize_cpu_ms": 1e3 * final_opt,
        "optimize_ms_max": 1e3 * max(eng.optimize_times, default=0.0),
        "loop_closures": s.loop_closures, "loop_rejected": s.loop_rejected, "odom_jumps": s.odom_jumps,
        "wide_searches": s.wide_searches, "scans_reordered": s.scans_reordered,
        "scans_skipped_time": s.scans_skipped_time, "match_failures": s.match_failures,
        "nodes_pruned": s.nodes_pruned, "loop_reject_reasons": dict(reasons.counts),
    }
    rel = data / f"{name}.relations"
    if rel.exists():
        row["relations"] = score_relations(read_relations(rel), stamps, poses).to_dict()
        if max_scans is None:
            odo = score_relations(read_relations(rel), stamps, odom).to_dict()
            row["odometry_relations_trans_mean"] = odo["trans_mean"]
    row["revisits"] = revisit_consistency(eng)
    return row, eng


def revisit_consistency(eng: SlamEngine) -> dict:
    """Direct scan-to-scan matches at revisited places vs the graph: translational disagreement (m)."""
    c = eng.config
    poses, path, pts = eng.graph.poses, np.asarray(eng._path), eng._points
    pairs = []
    for k in range(len(poses)):
        old = np.flatnonzero(path[k] - path[:k] >= REVISIT_PATH_M)
        if len(old) == 0:
            continue
        d = np.hypot(*(poses[old, :2] - poses[k, :2]).T)
        dth = np.abs(np.remainder(poses[old, 2] - poses[k, 2] + math.pi, 2 * math.pi) - math.pi)
        ok = (d < 0.5) & (dth < 0.5)
        if ok.any():
            pairs.append((int(old[ok][np.argmin(d[ok])]), k))
    if not pairs:
        return {"pairs": 0}
    sel = [pairs[i] for i in np.linspace(0, len(pairs) - 1, min(REVISIT_SAMPLES, len(pairs))).astype(int)]
    errs, overlaps = [], []
    wxy = 0.5
    margin = required_margin(wxy, c.coarse_factor, c.smear_sigma, c.resolution)
    for j, k in sel:
        ref = transform_points(poses[j], pts[j])
        lk = LookupGrid.from_points(ref, c.resolution, c.smear_sigma, margin)
        m = match_scan(lk, pts[k], poses[k], window_xy=wxy, window_theta=0.2, angular_step=c.angular_step,
                       coarse_factor=c.coarse_factor, sigma=c.smear_sigma, penalty=0.0)
        ov = inlier_fraction(lk, pts[k], m.pose, 0.1)
        if ov < 0.5:  # the two views barely overlap: the match says nothing
            continue
        e = relative(m.pose, poses[k])
        errs.append(math.hypot(e[0], e[1]))
        overlaps.append(ov)
    a = np.asarray(errs)
    if len(a) == 0:
        return {"pairs": len(pairs), "checked": 0}
    return {"pairs": len(pairs), "checked": len(a), "disagreement_mean_m": float(a.mean()),
            "disagreement_p95_m": float(np.percentile(a, 95)), "disagreement_max_m": float(a.max()),
            "over_0p2m": int((a > 0.2).sum())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--logs", nargs="*", default=list(LOGS), choices=LOGS)
    ap.add_argument("--max-scans", type=int, default=None, help="first N FLASER lines of each log (slices)")
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE",
                    help="SlamConfig overrides for experiments (the acceptance figures use none)")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "slam_public.json"))
    args = ap.parse_args()
    overrides = {}
    for kv in args.set:
        k, _, v = kv.partition("=")
        overrides[k] = json.loads(v)
    try:
        config = SlamConfig.from_dict(overrides)
    except ValueError as exc:
        print(f"slam_public: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    data = Path(args.data)
    out = Path(args.out)
    png_dir = out.parent / "slam_public"
    png_dir.mkdir(parents=True, exist_ok=True)
    load_numeric_stack()
    kernels.load()
    rows = []
    print(f"{'log':<10} {'scans':>6} {'nodes':>5} {'trans m':>15} {'rot deg':>13} {'p95 m':>6} {'p50 ms':>6} "
          f"{'p99 ms':>6} {'max ms':>7} {'>250':>4} {'scan/s':>6} {'LC':>4} {'rej':>4} {'jumps':>5} {'revisit':>8}")
    for name in args.logs:
        row, eng = run_log(name, data, args.max_scans, config)
        rows.append(row)
        (png_dir / f"{name}.png").write_bytes(render_map_png(eng.map()))
        r = row.get("relations")
        rv = row["revisits"].get("disagreement_p95_m", float("nan"))
        tr = f"{r['trans_mean']:.4f}+-{r['trans_std']:.3f}" if r else "-"
        ro = f"{r['rot_mean_deg']:.2f}+-{r['rot_std_deg']:.2f}" if r else "-"
        p95 = f"{r['trans_p95']:.3f}" if r else "-"
        print(f"{name:<10} {row['scans']:>6} {row['nodes']:>5} {tr:>15} {ro:>13} {p95:>6} {row['cpu_ms_p50']:>6.1f} "
              f"{row['cpu_ms_p99']:>6.1f} {row['cpu_ms_max']:>7.0f} {row['calls_over_250ms']:>4} "
              f"{row['scans_per_s']:>6.0f} {row['loop_closures']:>4} {row['loop_rejected']:>4} "
              f"{row['odom_jumps']:>5} {rv:>8.3f}", flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"bench": "slam_public", "max_scans": args.max_scans, "overrides": overrides,
                               "machine": platform.machine(), "python": platform.python_version(),
                               "rows": rows}, indent=2))
    print(f"wrote {out} and {png_dir}/*.png")


if __name__ == "__main__":
    main()
