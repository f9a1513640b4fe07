"""Planner + controller benchmark, in the style of Nav2's planner benchmark.

    python bench/planner_bench.py [--pairs 100] [--size 2000] [--seed 0]

Generates 2000×2000 maps at 0.05 m (100 m × 100 m) with ~10/15/20 % obstacle density (random boxes and
discs), builds the inflated costmap (inflation_radius 0.55 m, cost_scaling_factor 3.0, panda_mobile
footprint), and plans between seeded random start/goal pairs 60–95 m apart in the same free component.
Reports median/p95 plan time per density, path length vs (a) the straight-line lower bound and (b) the
exact cost-optimal 8-connected path (A* with weight 1.0, unsmoothed = Dijkstra-equivalent), the A* cost vs
that optimum, and the controller's compute time per step. Writes bench/results/planner.json.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nav2_wrapper.core import (
    INSCRIBED,
    ControllerConfig,
    Costmap,
    CostmapConfig,
    GlobalPlanner,
    HolonomicController,
    PlannerConfig,
)
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

RES = 0.05
ANCHORS_MS = {"Smac 2D": 243.0, "NavFn": 146.0, "Theta*": 46.0}   # published Nav2 C++ figures, ~75–88 m paths
OUT = Path(__file__).resolve().parent / "results" / "planner.json"


def make_map(size: int, density: float, rng: np.random.Generator) -> np.ndarray:
    occ = np.zeros((size, size), bool)
    yy, xx = np.mgrid[-20:21, -20:21]
    while occ.mean() < density:
        for _ in range(max(1, int((density - occ.mean()) * size * size / 600))):
            r, c = rng.integers(0, size, 2)
            if rng.random() < 0.7:
                h, w = rng.integers(4, 41, 2)
                occ[r:r + h, c:c + w] = True
            else:
                rad = int(rng.integers(3, 21))
                disc = (yy ** 2 + xx ** 2) <= rad * rad
                r0, c0 = max(0, r - 20), max(0, c - 20)
                sub = disc[r0 - (r - 20):, c0 - (c - 20):][: size - r0, : size - c0]
                occ[r0:r0 + sub.shape[0], c0:c0 + sub.shape[1]] |= sub
    return np.where(occ, 100, 0).astype(np.int8)


def pick_pairs(cm: Costmap, n: int, rng: np.random.Generator) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    free = cm.costs < INSCRIBED
    lab, _ = ndimage.label(free)   # 4-connected: the planner forbids diagonal squeezes between blocked cells
    big = np.bincount(lab.ravel())[1:].argmax() + 1
    cells = np.argwhere(lab == big)
    pairs = []
    while len(pairs) < n:
        a, b = cells[rng.integers(len(cells))], cells[rng.integers(len(cells))]
        d = math.hypot(*(a - b)) * RES
        if 60.0 <= d <= 95.0:
            sa, sb = cm.cell_to_world(a[1], a[0]), cm.cell_to_world(b[1], b[0])
            pairs.append(((float(sa[0]), float(sa[1])), (float(sb[0]), float(sb[1]))))
    return pairs


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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=100)
    ap.add_argument("--size", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--weight", type=float, default=PlannerConfig.heuristic_weight, help="A* heuristic weight")
    ap.add_argument("--densities", type=float, nargs="+", default=[0.10, 0.15, 0.20])
    ap.add_argument("--no-exact", action="store_true", help="skip the exact-optimum comparison (faster)")
    args = ap.parse_args()
    fp = load_footprint()
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=args.weight))
    exact = GlobalPlanner(PlannerConfig(heuristic_weight=1.0, smooth_path=False))
    results: dict = {"machine": platform.processor() or platform.machine(), "pairs": args.pairs,
                     "size": args.size, "resolution": RES, "anchors_ms": ANCHORS_MS,
                     "planner": {"heuristic_weight": planner.cfg.heuristic_weight,
                                 "cost_travel_multiplier": planner.cfg.cost_travel_multiplier},
                     "densities": {}}
    t_compile = time.perf_counter()
    warm = Costmap(CostmapConfig(obstacle_layer=False, footprint=fp))
    warm.set_static_map(GridMap(np.zeros((50, 50), np.int8), RES))
    planner.plan(warm, (0.3, 0.3), (2.0, 2.0))
    results["first_call_s"] = round(time.perf_counter() - t_compile, 3)
    print(f"numba first call (cache load/compile): {results['first_call_s']:.2f} s")
    print("published Nav2 C++ anchors: " + ", ".join(f"{k} {v:.0f} ms" for k, v in ANCHORS_MS.items()))
    ctrl_times: list[float] = []
    for i, dens in enumerate(args.densities):
        rng = np.random.default_rng(args.seed + i)
        grid = GridMap(make_map(args.size, dens, rng), RES)
        cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.55, cost_scaling_factor=3.0,
                                   track_unknown_space=True, footprint=fp))
        t0 = time.perf_counter()
        cm.set_static_map(grid)
        t_costmap = time.perf_counter() - t0
        pairs = pick_pairs(cm, args.pairs, rng)
        times, lens, straight, len_ratio, cost_ratio, fails = [], [], [], [], [], 0
        for s, g in pairs:
            t0 = time.perf_counter()
            r = planner.plan(cm, s, g)
            times.append(time.perf_counter() - t0)
            if not r.ok:
                fails += 1
                continue
            lens.append(r.length)
            straight.append(r.length / math.hypot(g[0] - s[0], g[1] - s[1]))
            if not args.no_exact:
                e = exact.plan(cm, s, g)
                len_ratio.append(r.length / e.length)
                cost_ratio.append(r.cost / e.cost)
        ms = np.array(times) * 1e3
        row = {"obstacle_density": round(float((grid.data == 100).mean()), 3), "costmap_build_s": round(t_costmap, 3),
               "plan_ms_median": round(float(np.median(ms)), 2), "plan_ms_p95": round(float(np.percentile(ms, 95)), 2),
               "plan_ms_max": round(float(ms.max()), 2), "failures": fails,
               "path_m_median": round(float(np.median(lens)), 2),
               "length_vs_straight_line_median": round(float(np.median(straight)), 4)}
        if len_ratio:
            row["length_vs_exact_optimal_median"] = round(float(np.median(len_ratio)), 4)
            row["length_vs_exact_optimal_max"] = round(float(np.max(len_ratio)), 4)
            row["cost_vs_exact_optimal_median"] = round(float(np.median(cost_ratio)), 4)
            row["cost_vs_exact_optimal_max"] = round(float(np.max(cost_ratio)), 4)
        results["densities"][f"{dens:.2f}"] = row
        print(f"density {row['obstacle_density']:.2f}: plan median {row['plan_ms_median']:.1f} ms, "
              f"p95 {row['plan_ms_p95']:.1f} ms, max {row['plan_ms_max']:.1f} ms, "
              f"path median {row['path_m_median']:.1f} m, "
              f"length/straight {row['length_vs_straight_line_median']:.3f}"
              + (f", length/exact-optimal {row['length_vs_exact_optimal_median']:.3f}, "
                 f"cost/exact-optimal {row['cost_vs_exact_optimal_median']:.3f} "
                 f"(max {row['cost_vs_exact_optimal_max']:.3f})"
                 if len_ratio else "") + f", failures {fails}, costmap build {t_costmap:.2f} s")
        s, g = pairs[0]
        ctrl_times += controller_step_times(cm, planner.plan(cm, s, g).path, g)
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
