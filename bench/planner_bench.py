"""Global planner benchmark with its peer in the same run, plus the controller's step time.

    pip install -c constraints.txt -e '.[bench]'       # pyastar2d, the peer
    python bench/planner_bench.py [--pairs 100] [--size 2000] [--seed 0] [--weight 1.0]

Generates 2000×2000 maps at 0.05 m (100 m × 100 m) with ~10/15/20 % obstacle density (random boxes and
discs), builds the inflated costmap (inflation_radius 0.55 m, cost_scaling_factor 3.0, panda_mobile
footprint), and plans between seeded random start/goal pairs in the same free component: 100 pairs ≥ 3 m
apart ("near", the issue's setting) and 100 pairs 60–95 m apart ("far"). Our planner runs with the robot
profiles' settings (heuristic_weight 1.0 = cost-optimal, cost_travel_multiplier 2.0, smoothing on).

The peer, pyastar2d (a C++ grid A*), plans each pair right after ours on the same cell weights: our
traversal factor per cell (1 + 2·cost/252, inf for inscribed/lethal). Its cost model differs in one way
that cannot be configured: a diagonal move costs the entered cell's weight, not √2 times it (and it may
squeeze diagonally between two blocked cells). So the costs are compared in our model: its path, costed as
we cost moves, must never be cheaper than ours (ours is optimal in that model), and the ratio is reported.
Reports median/p95/max plan time per density and setting (wall clock, and the planning thread's CPU
time, which a loaded machine inflates far less), our time / peer time, expansions, the load average at
start and end, and the controller's compute time per step. Writes bench/results/planner.json.

Every pair is also planned by the reference planner (``nav2_wrapper.core.reference``, a textbook A*): ours
must never be costlier (``costlier_than_reference`` counts the pairs where it is, to a relative 1e-5; float32
g), and its time is reported beside.

``--ab-width W`` compares bucket widths instead (no peer, no controller): each pair is planned at the default
``bucket_width`` and at W back to back (order alternating per pair); per width the CPU time and queue pops
(expansions) are reported, plus the median of the paired CPU ratios and a check that both found the same cost.
Writes bench/results/planner_ab.json.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

from nav2_wrapper.core import (
    ControllerConfig,
    Costmap,
    CostmapConfig,
    GlobalPlanner,
    HolonomicController,
    PlannerConfig,
)
from nav2_wrapper.core.reference import reference_plan
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap
from robonix_eval.planner_maps import RES, SETTINGS, Cell, make_map, pick_pairs, world

OUT = Path(__file__).resolve().parent / "results" / "planner.json"
OUT_AB = OUT.with_name("planner_ab.json")
DEFAULT_WIDTH = PlannerConfig().bucket_width


def path_cost(costs: np.ndarray, table: np.ndarray, path: np.ndarray) -> float:
    """Cost of a cell path (rows of (row, col)) in our model: entered cell's factor × step length, inf through
    a blocked cell or a diagonal squeeze between two blocked cells (start outside any blocked cell)."""
    r, c = path[:, 0], path[:, 1]
    f = table[costs[r[1:], c[1:]]]
    diag = (r[1:] != r[:-1]) & (c[1:] != c[:-1])
    squeeze = diag & np.isinf(table[costs[r[:-1], c[1:]]]) & np.isinf(table[costs[r[1:], c[:-1]]])
    if squeeze.any():
        return math.inf
    return float(np.sum(f * np.where(diag, math.sqrt(2.0), 1.0)))


class Peer:
    """pyastar2d on our cell weights (the C entry point, so its time is the search, not the wrapper's copy)."""

    def __init__(self, costs: np.ndarray, table: np.ndarray) -> None:
        import pyastar2d  # optional: only the benchmark needs it

        self._astar = pyastar2d.astar.astar
        self.rows, self.cols = costs.shape
        self.weights = table.astype(np.float32)[costs].ravel()

    def plan(self, start: Cell, goal: Cell) -> np.ndarray | None:
        return self._astar(self.weights, self.rows, self.cols, start[0] * self.cols + start[1],
                           goal[0] * self.cols + goal[1], True, 0)


def stats(ms: list[float]) -> dict[str, float]:
    a = np.asarray(ms)
    return {"median": round(float(np.median(a)), 2), "p95": round(float(np.percentile(a, 95)), 2),
            "max": round(float(a.max()), 2)}


def run_setting(cm: Costmap, planner: GlobalPlanner, peer: Peer | None, pairs: list[tuple[Cell, Cell]]) -> dict:
    """Each pair: our plan, then the peer's, timed back to back (the machine's load hits both alike)."""
    table = planner.traversal_table()
    ours, theirs, expansions, ratio, fails, peer_fails, cheaper, squeezes = [], [], [], [], 0, 0, 0, 0
    ours_cpu, theirs_cpu, ref_ms, costlier = [], [], [], 0
    esc_r2 = (planner.cfg.escape_radius / RES) ** 2
    esc_cost = 1.0 + planner.cfg.cost_travel_multiplier * 2.0
    for s, g in pairs:
        t0, c0 = time.perf_counter(), time.thread_time()
        r = planner.plan(cm, world(cm, s), world(cm, g))
        ours.append((time.perf_counter() - t0) * 1e3)
        ours_cpu.append((time.thread_time() - c0) * 1e3)
        expansions.append(r.expansions)
        fails += not r.ok
        t0 = time.perf_counter()
        ref = reference_plan(cm.costs, table, s, g, esc_r2, esc_cost)
        ref_ms.append((time.perf_counter() - t0) * 1e3)
        costlier += (not r.ok and math.isfinite(ref.cost)) or (r.ok and r.cost > ref.cost * (1 + 1e-5))
        if peer is None:
            continue
        t0, c0 = time.perf_counter(), time.thread_time()
        p = peer.plan(s, g)
        theirs.append((time.perf_counter() - t0) * 1e3)
        theirs_cpu.append((time.thread_time() - c0) * 1e3)
        if p is None:
            peer_fails += 1
            continue
        pc = path_cost(cm.costs, table, np.asarray(p))
        if not math.isfinite(pc):
            squeezes += 1
        elif r.ok:
            ratio.append(pc / r.cost)
            cheaper += pc < r.cost * (1 - 1e-5)
    row: dict = {"ours_ms": stats(ours), "ours_cpu_ms": stats(ours_cpu),
                 "expansions_median": int(np.median(expansions)), "failures": fails,
                 "reference_ms": stats(ref_ms), "costlier_than_reference": int(costlier)}
    if peer is not None:
        row.update({"peer_ms": stats(theirs), "peer_cpu_ms": stats(theirs_cpu), "peer_failures": peer_fails,
                    "ours_over_peer_cpu_median": round(row["ours_cpu_ms"]["median"] / stats(theirs_cpu)["median"], 3),
                    "ours_over_peer_median": round(row["ours_ms"]["median"] / stats(theirs)["median"], 3),
                    "ours_over_peer_p95": round(row["ours_ms"]["p95"] / stats(theirs)["p95"], 3),
                    "peer_path_cost_over_ours_median": round(float(np.median(ratio)), 4) if ratio else None,
                    "peer_path_cost_over_ours_min": round(float(np.min(ratio)), 6) if ratio else None,
                    "peer_paths_cheaper_than_ours": int(cheaper), "peer_paths_squeezing_diagonally": squeezes})
    return row


def ab_variants(width_b: float) -> dict[str, float]:
    """The two bucket widths ``--ab-width`` compares, the reference (the ratios' denominator) last."""
    return {f"width {DEFAULT_WIDTH:g}": DEFAULT_WIDTH, f"width {width_b:g}": width_b}


def run_ab(cm: Costmap, planner: GlobalPlanner, pairs: list[tuple[Cell, Cell]], variants: dict[str, float]) -> dict:
    """Each pair planned by both variants back to back, alternating which goes first."""
    names = list(variants)
    ref = names[-1]
    cpu: dict[str, list[float]] = {k: [] for k in names}
    pops: dict[str, list[int]] = {k: [] for k in names}
    ratio: dict[str, list[float]] = {k: [] for k in names}
    cost_mismatch = 0
    for i, (s, g) in enumerate(pairs):
        costs = {}
        for name in names if i % 2 == 0 else names[::-1]:
            planner.cfg.bucket_width = variants[name]
            c0 = time.thread_time()
            r = planner.plan(cm, world(cm, s), world(cm, g))
            cpu[name].append((time.thread_time() - c0) * 1e3)
            pops[name].append(r.expansions)
            costs[name] = r.cost if r.ok else math.inf
        for k in names:
            ratio[k].append(cpu[k][-1] / max(cpu[ref][-1], 1e-6))
        # float32 g: on 60-95 m paths the kernels report the same path's cost up to ~1e-5 apart (seen: 1.1e-5)
        cost_mismatch += any(not math.isclose(costs[k], costs[ref], rel_tol=5e-5) for k in names)
    planner.cfg.bucket_width = DEFAULT_WIDTH
    row: dict = {k: {"cpu_ms": stats(cpu[k]), "pops_median": int(np.median(pops[k])),
                     "cpu_over_reference_median_of_paired_ratios": round(float(np.median(ratio[k])), 3)}
                 for k in names}
    row["reference"] = ref
    row["cost_mismatches"] = cost_mismatch
    return row


def controller_step_times(cm: Costmap, plan_path: np.ndarray, goal: tuple[float, float],
                          steps: int = 400) -> list[float]:
    """Time HolonomicController.compute on a 4 m rolling local costmap along a real path (integrator loop)."""
    fp = load_footprint()
    local = Costmap(CostmapConfig(name="local", rolling_window=True, width=4.0, height=4.0, obstacle_layer=False,
                                  cost_scaling_factor=3.0, inflation_radius=0.55, footprint=fp))
    grid = GridMap(np.where(cm.static == 254, 100, 0).astype(np.int8), RES)
    local.set_static_map(grid)
    ctrl = HolonomicController(ControllerConfig(footprint=fp))
    ctrl.set_path(plan_path)
    x, y = plan_path[0]
    th, vel, dt = 0.0, (0.0, 0.0, 0.0), 0.05
    times = []
    for _ in range(steps):
        local.update_origin(x, y)
        t0 = time.perf_counter()
        out = ctrl.compute((x, y, th), vel, (goal[0], goal[1], 0.0), local, dt)
        times.append(time.perf_counter() - t0)
        c, s = math.cos(th), math.sin(th)
        x, y, th = x + (c * out.vx - s * out.vy) * dt, y + (s * out.vx + c * out.vy) * dt, th + out.wz * dt
        vel = (out.vx, out.vy, out.wz)
    return times


def parse_args() -> argparse.Namespace:
    """The command line, with the experiment overrides applied to the planner module."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=100)
    ap.add_argument("--size", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--weight", type=float, default=1.0,
                    help="A* heuristic weight (1.0 = cost-optimal, what the robot profiles use)")
    ap.add_argument("--densities", type=float, nargs="+", default=[0.10, 0.15, 0.20])
    ap.add_argument("--settings", nargs="+", default=list(SETTINGS), choices=list(SETTINGS))
    ap.add_argument("--no-peer", action="store_true", help="skip pyastar2d")
    ap.add_argument("--ab-width", type=float, metavar="W",
                    help="paired A/B of the default bucket width vs W (no peer, no controller)")
    args = ap.parse_args()
    args.ab = args.ab_width is not None
    if args.ab:
        if not args.ab_width > 0:
            ap.error(f"--ab-width must be > 0, got {args.ab_width}")
        args.no_peer = True
    return args


def main() -> None:
    args = parse_args()
    try:
        import pyastar2d  # noqa: F401
        use_peer = not args.no_peer
    except ImportError:
        print("pyastar2d is not installed (pip install -c constraints.txt -e '.[bench]'): no peer in this run")
        use_peer = False
    fp = load_footprint()
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=args.weight))
    variants = ab_variants(args.ab_width) if args.ab else {}
    results: dict = {"machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
                     "load_avg_at_start": os.getloadavg()[0], "pairs": args.pairs, "size": args.size,
                     "resolution": RES, "peer": "pyastar2d" if use_peer else None,
                     "planner": {"heuristic_weight": planner.cfg.heuristic_weight,
                                 "cost_travel_multiplier": planner.cfg.cost_travel_multiplier},
                     "settings_m": {k: list(SETTINGS[k]) for k in args.settings}, "densities": {},
                     "bucket_width": DEFAULT_WIDTH}
    if args.ab:
        results["ab_variants"] = variants
    t_compile = time.perf_counter()
    warm = Costmap(CostmapConfig(obstacle_layer=False, footprint=fp))
    warm.set_static_map(GridMap(np.zeros((50, 50), np.int8), RES))
    planner.plan(warm, (0.3, 0.3), (2.0, 2.0))
    reference_plan(warm.costs, planner.traversal_table(), (5, 5), (40, 40))
    results["first_call_s"] = round(time.perf_counter() - t_compile, 3)
    print(f"numba first call (cache load/compile): {results['first_call_s']:.2f} s")
    ctrl_times: list[float] = []
    for i, dens in enumerate(args.densities):
        rng = np.random.default_rng(args.seed + i)
        grid = GridMap(make_map(args.size, dens, rng), RES)
        cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.55, cost_scaling_factor=3.0,
                                   track_unknown_space=True, footprint=fp))
        cm.set_static_map(grid)
        peer = Peer(cm.costs, planner.traversal_table()) if use_peer else None
        if peer is not None:
            peer.plan((0, 0), (0, 0))
        row: dict = {"obstacle_density": round(float((grid.data == 100).mean()), 3)}
        for name in args.settings:
            pairs = pick_pairs(cm, args.pairs, rng, *SETTINGS[name])
            if args.ab:
                r = row[name] = run_ab(cm, planner, pairs, variants)
                print(f"density {row['obstacle_density']:.2f} {name:4s}: " + " | ".join(
                    f"{k} CPU ms median {r[k]['cpu_ms']['median']:.2f} p95 {r[k]['cpu_ms']['p95']:.2f} "
                    f"(x{r[k]['cpu_over_reference_median_of_paired_ratios']} {r['reference']}, paired), pops "
                    f"{r[k]['pops_median']}" for k in variants)
                    + f" | cost mismatches {r['cost_mismatches']}", flush=True)
                continue
            r = row[name] = run_setting(cm, planner, peer, pairs)
            line = (f"density {row['obstacle_density']:.2f} {name:4s}: ours median {r['ours_ms']['median']:.1f} ms, "
                    f"p95 {r['ours_ms']['p95']:.1f}, max {r['ours_ms']['max']:.1f} "
                    f"(CPU median {r['ours_cpu_ms']['median']:.1f}, p95 {r['ours_cpu_ms']['p95']:.1f}; "
                    f"{r['expansions_median']} expansions median, {r['failures']} failures) | reference A* median "
                    f"{r['reference_ms']['median']:.0f} ms, ours costlier on {r['costlier_than_reference']} pairs")
            if peer is not None:
                line += (f" | pyastar2d median {r['peer_ms']['median']:.1f} ms, p95 {r['peer_ms']['p95']:.1f}, "
                         f"max {r['peer_ms']['max']:.1f} (CPU median {r['peer_cpu_ms']['median']:.1f}, "
                         f"p95 {r['peer_cpu_ms']['p95']:.1f}) | ours/peer {r['ours_over_peer_median']:.2f} (median), "
                         f"{r['ours_over_peer_cpu_median']:.2f} (CPU median), "
                         f"{r['ours_over_peer_p95']:.2f} (p95) | peer path cost/ours median "
                         f"{r['peer_path_cost_over_ours_median']}, min {r['peer_path_cost_over_ours_min']}, "
                         f"{r['peer_paths_cheaper_than_ours']} cheaper, "
                         f"{r['peer_paths_squeezing_diagonally']} squeezing")
            print(line, flush=True)
        results["densities"][f"{dens:.2f}"] = row
        if args.ab:
            continue
        s, g = pick_pairs(cm, 1, rng, *SETTINGS["far"])[0]
        ctrl_times += controller_step_times(cm, planner.plan(cm, world(cm, s), world(cm, g)).path, world(cm, g))
    results["load_avg_at_end"] = os.getloadavg()[0]
    if args.ab:
        OUT_AB.parent.mkdir(parents=True, exist_ok=True)
        OUT_AB.write_text(json.dumps(results, indent=2) + "\n")
        print(f"load average {results['load_avg_at_start']:.1f} -> {results['load_avg_at_end']:.1f}; wrote {OUT_AB}")
        return
    cms = np.array(ctrl_times) * 1e3
    results["controller_ms_median"] = round(float(np.median(cms)), 3)
    results["controller_ms_p95"] = round(float(np.percentile(cms, 95)), 3)
    print(f"controller compute per step: median {results['controller_ms_median']:.2f} ms, "
          f"p95 {results['controller_ms_p95']:.2f} ms (goal ≤ 10 ms, i.e. ≥ 100 Hz)")
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
