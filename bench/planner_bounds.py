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
- ``band``: cells with g + h_band < C*, h_band = max(octile, climb, descent), a bound from the distance field
  that costs one lookup per cell. The distance to the nearest lethal cell changes by at most one step length
  per step, and a cell's traversal factor is at least its inflation factor at that distance, so a path from a
  cell at clearance a must pay the band it climbs out of (climb = L + E(a + √2) − E(b + √2)) and a path into a
  goal at clearance b the band it descends into (descent = L + E(b) − E(b + L)), with E(x) the excess factor
  integrated from x outward and L the octile distance. Both are admissible and consistent (the √2 covers the
  entered-cell convention), so their max is too. It says whether the ends of a route carry the excess.
- ``uniform_share``: the share of the ``octile_min`` cells whose 3×3 neighbourhood is all cost 0 (factor 1):
  the cells a jumping search (JPS-style runs instead of queue entries) could pass over.

Writes bench/results/planner_bounds.json.
"""

from __future__ import annotations

import argparse
import heapq
import json
import math
import os
import time
from pathlib import Path

import numpy as np
from numba import njit
from scipy import ndimage

import robonix_eval.planner_maps as pb  # the bench's maps and pairs
from nav2_wrapper.core import Costmap, CostmapConfig, GlobalPlanner, PlannerConfig
from nav2_wrapper.core.costs import LETHAL, inflation_cost
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


E_STEP = 1.0 / 64      # cells: sampling of the excess integral


def excess_integral(table: np.ndarray, cm: Costmap) -> np.ndarray:
    """E[i] = ∫ from i·E_STEP outward of (φ(s) − 1) ds in cells, φ(s) the lowest traversal factor a cell at
    distance s (cells) from the nearest lethal cell can have: its inflation factor, capped by the unknown
    cell's factor (unknown cells keep their own cost outside the inscribed radius). Made non-increasing and
    summed with each interval at its right end, so E never overstates."""
    fp, cfg = cm.cfg.footprint, cm.cfg
    s = np.arange(0.0, cfg.inflation_radius / cm.resolution + 4.0, E_STEP)
    phi = table[inflation_cost(s * cm.resolution, fp.inscribed_radius, cfg.inflation_radius,
                               cfg.cost_scaling_factor)]
    finite = np.isfinite(phi)
    phi = np.minimum(np.where(finite, phi, phi[finite].max()), table[255])  # inside the inscribed radius: never entered
    excess = np.minimum.accumulate(phi - float(table.min()))
    right = np.append(excess[1:], 0.0) * E_STEP
    return np.cumsum(right[::-1])[::-1]


def excess_at(e: np.ndarray, x: np.ndarray | float) -> np.ndarray:
    i = np.floor(np.asarray(x) / E_STEP).astype(np.int64) + 1        # one sample further out: a lower bound
    return np.where(i < len(e), e[np.minimum(i, len(e) - 1)], 0.0)


def band_bound(e: np.ndarray, clearance: np.ndarray, octile: np.ndarray, goal: int) -> np.ndarray:
    b = clearance[goal]
    climb = octile + excess_at(e, clearance + SQRT2) - excess_at(e, b + SQRT2)
    descent = octile + excess_at(e, b) - excess_at(e, b + octile)
    return np.maximum(octile, np.maximum(climb, descent))


def pair_bounds(weights: np.ndarray, s: pb.Cell, g: pb.Cell, blocks: list[int], band: tuple) -> dict:
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
    e, clearance, uniform = band
    must = f < best - tol
    h_band = band_bound(e, clearance, h_fwd, gf)
    reach = np.isfinite(g_bwd)
    assert np.all(h_band[reach] <= g_bwd[reach] + tol), "band bound above the exact cost-to-go"
    out["band"] = int((g_fwd + h_band < best - tol).sum())
    out["uniform_share"] = round(float((must & uniform).sum() / max(int(must.sum()), 1)), 3)
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
    keys = ["octile_min", "octile_ties", "two_sided", "band"] + [f"blockmin_{b}" for b in args.blocks]
    results: dict = {"pairs": args.pairs, "size": args.size, "load_avg_at_start": os.getloadavg()[0],
                     "densities": {}}
    t0 = time.perf_counter()
    for i, dens in enumerate(args.densities):
        rng = np.random.default_rng(args.seed + i)
        cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.55, cost_scaling_factor=3.0,
                                   track_unknown_space=True, footprint=fp))
        cm.set_static_map(GridMap(pb.make_map(args.size, dens, rng), pb.RES))
        table = planner.traversal_table()
        weights = table[cm.costs]
        band = (excess_integral(table, cm), ndimage.distance_transform_edt(cm.costs != LETHAL).ravel(),
                (ndimage.maximum_filter(cm.costs, size=3) == 0).ravel())
        row: dict = {}
        for name in args.settings:
            if pb.SETTINGS[name][0] > args.size * pb.RES * SQRT2:
                continue                    # no pair that far apart on this map (pick_pairs would never end)
            per_pair = []
            for s, g in pb.pick_pairs(cm, args.pairs, rng, *pb.SETTINGS[name]):
                r = planner.plan(cm, pb.world(cm, s), pb.world(cm, g))
                b = pair_bounds(weights, s, g, args.blocks, band)
                assert r.ok, r.reason
                assert abs(r.cost - b["cost"]) <= 1e-4 * b["cost"], (r.cost, b["cost"])   # float32 g: ~1e-5 off
                per_pair.append({"expansions": r.expansions, **b})
            summary = summarise(per_pair, keys)
            summary["uniform_share_median"] = round(float(np.median([p["uniform_share"] for p in per_pair])), 3)
            row[name] = {"summary": summary, "pairs": per_pair}
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
