"""How far the cost-optimal planner is from what any search with a given heuristic must expand (issue 21).

    python bench/planner_bounds.py [--pairs 5] [--size 2000] [--densities 0.10 0.15 0.20] [--blocks 4 8]

Same maps and pair settings as ``planner_bench.py`` (fewer pairs: every pair costs several full-map Dijkstra
sweeps here). For each pair it computes, with plain heap Dijkstra sweeps written independently of the
planner's kernel (exact g from the start, exact cost-to-go to the goal):

- ``octile_min``: cells with g + octile < C*. Every A* with the octile heuristic (ours: h = octile × 1.0)
  must expand all of them, whatever its queue or tie-breaking; ``octile_ties`` adds the cells with f = C*
  exactly, which only tie-breaking can avoid. Our expansions over these says what queue tuning can still gain.
- ``two_sided``: cells a front-to-end bidirectional search with the reverse-corrected key 2g + h − h_other
  (the DIBBS / BAE* family, stopping rule (min key_fwd + min key_bwd) / 2 ≥ best meeting cost) expands when
  both sides meet at key C*: the idealised count, no meeting overhead.
- ``blockmin_B``: cells with g + h_B < C* where h_B = max(octile, the exact cost-to-go in the relaxed grid in
  which every cell costs the cheapest traversable factor of its B×B block and fully blocked blocks stay
  blocked). h_B is admissible and consistent (exact distance in a graph whose moves cost no more), so this
  is what a heuristic that knows the cost bands at B-cell resolution would expand. Computing h_B exactly is
  a full sweep, as dear as the search itself: the figure says what a cheap bound of that strength would buy.

Writes bench/results/planner_bounds.json.
"""

from __future__ import annotations

import argparse
import heapq
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import planner_bench as pb  # the bench's maps and pairs

from nav2_wrapper.core import Costmap, CostmapConfig, GlobalPlanner, PlannerConfig
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

OUT = Path(__file__).resolve().parent / "results" / "planner_bounds.json"
SQRT2 = math.sqrt(2.0)
DRS = np.array([-1, 1, 0, 0, -1, -1, 1, 1])
DCS = np.array([0, 0, -1, 1, -1, 1, -1, 1])


@njit(cache=True)
def sweep(weights, rows, cols, source, to_source):
    """Exact costs on the 8-connected grid (a move costs the entered cell's weight × step length, inf weight =
    blocked, no diagonal squeeze between two blocked orthogonal cells): from ``source`` to every cell, or,
    with ``to_source``, from every cell to ``source``."""
    dist = np.full(rows * cols, np.inf)
    dist[source] = 0.0
    heap = [(0.0, source)]
    while len(heap):
        d, u = heapq.heappop(heap)
        if d > dist[u]:
            continue
        r, c = u // cols, u % cols
        for k in range(8):
            nr, nc = r + DRS[k], c + DCS[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            v = nr * cols + nc
            if weights[v] == np.inf:
                continue
            step = 1.0
            if k >= 4:
                if weights[r * cols + nc] == np.inf and weights[nr * cols + c] == np.inf:
                    continue
                step = SQRT2
            nd = d + (weights[u] if to_source else weights[v]) * step
            if nd < dist[v]:
                dist[v] = nd
                heapq.heappush(heap, (nd, v))
    return dist


def octile_to(rows: int, cols: int, cell: tuple[int, int]) -> np.ndarray:
    rr, cc = np.mgrid[0:rows, 0:cols]
    dr, dc = np.abs(rr - cell[0]), np.abs(cc - cell[1])
    return (dr + dc + (SQRT2 - 2.0) * np.minimum(dr, dc)).ravel()


def block_min(weights: np.ndarray, b: int) -> np.ndarray:
    """Each cell's weight replaced by the smallest in its b×b block (inf only if the whole block is)."""
    rows, cols = weights.shape
    nr, nc = -(-rows // b), -(-cols // b)
    pad = np.full((nr * b, nc * b), np.inf)
    pad[:rows, :cols] = weights
    m = pad.reshape(nr, b, nc, b).min(axis=(1, 3))
    return np.repeat(np.repeat(m, b, 0), b, 1)[:rows, :cols]


def pair_bounds(weights: np.ndarray, s: pb.Cell, g: pb.Cell, blocks: list[int]) -> dict:
    rows, cols = weights.shape
    flat = weights.ravel().copy()
    sf, gf = s[0] * cols + s[1], g[0] * cols + g[1]
    g_fwd = sweep(flat, rows, cols, sf, False)
    g_bwd = sweep(flat, rows, cols, gf, True)
    best = g_fwd[gf]
    h_fwd, h_bwd = octile_to(rows, cols, g), octile_to(rows, cols, s)
    f = g_fwd + h_fwd
    tol = 1e-9 * best
    out = {"cost": float(best), "octile_start": float(h_fwd[sf]),
           "octile_min": int((f < best - tol).sum()), "octile_ties": int((f <= best + tol).sum()),
           "two_sided": int((2 * g_fwd + h_fwd - h_bwd < best - tol).sum()
                            + (2 * g_bwd + h_bwd - h_fwd < best - tol).sum())}
    for b in blocks:
        h_b = np.maximum(h_fwd, sweep(block_min(weights, b).ravel().copy(), rows, cols, gf, True))
        out[f"blockmin_{b}"] = int((g_fwd + h_b < best - tol).sum())
    return out


def summarise(rows: list[dict], keys: list[str]) -> dict:
    ours = np.array([r["expansions"] for r in rows], float)
    summary = {"expansions_median": int(np.median(ours))}
    for k in keys:
        v = np.array([r[k] for r in rows], float)
        summary[f"{k}_median"] = int(np.median(v))
        summary[f"expansions_over_{k}_median"] = round(float(np.median(ours / np.maximum(v, 1))), 3)
    return summary


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--size", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--densities", type=float, nargs="+", default=[0.10, 0.15, 0.20])
    ap.add_argument("--settings", nargs="+", default=list(pb.SETTINGS), choices=list(pb.SETTINGS))
    ap.add_argument("--blocks", type=int, nargs="*", default=[4, 8])
    args = ap.parse_args()
    fp = load_footprint()
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=1.0))
    keys = ["octile_min", "octile_ties", "two_sided"] + [f"blockmin_{b}" for b in args.blocks]
    results: dict = {"pairs": args.pairs, "size": args.size, "load_avg_at_start": os.getloadavg()[0],
                     "densities": {}}
    t0 = time.perf_counter()
    for i, dens in enumerate(args.densities):
        rng = np.random.default_rng(args.seed + i)
        cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.55, cost_scaling_factor=3.0,
                                   track_unknown_space=True, footprint=fp))
        cm.set_static_map(GridMap(pb.make_map(args.size, dens, rng), pb.RES))
        weights = planner.traversal_table()[cm.costs]
        row: dict = {}
        for name in args.settings:
            if pb.SETTINGS[name][0] > args.size * pb.RES * SQRT2:
                continue                    # no pair that far apart on this map (pick_pairs would never end)
            per_pair = []
            for s, g in pb.pick_pairs(cm, args.pairs, rng, *pb.SETTINGS[name]):
                r = planner.plan(cm, pb.world(cm, s), pb.world(cm, g))
                b = pair_bounds(weights, s, g, args.blocks)
                assert r.ok, r.reason
                assert abs(r.cost - b["cost"]) <= 1e-4 * b["cost"], (r.cost, b["cost"])   # float32 g: ~1e-5 off
                per_pair.append({"expansions": r.expansions, **b})
            row[name] = {"summary": summarise(per_pair, keys), "pairs": per_pair}
            print(f"density {dens:.2f} {name:4s}: " + ", ".join(f"{k} {v}" for k, v in row[name]["summary"].items()),
                  flush=True)
        results["densities"][f"{dens:.2f}"] = row
    results["load_avg_at_end"] = os.getloadavg()[0]
    results["seconds"] = round(time.perf_counter() - t0, 1)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {OUT} ({results['seconds']} s)")


if __name__ == "__main__":
    main()
