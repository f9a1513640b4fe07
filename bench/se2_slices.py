"""How long one control tick stalls for the SE(2) fallback: set-up (window, collision grids, heuristic) and a
slice of ``tick_expansions`` states, on the fully known clutter worlds whose 2D path has no fitting heading.

    python bench/se2_slices.py [--only 41,74,94,2,8,14] [--slice 60000] [--out bench/results/se2_slices.json]

For each world: the 2D plan from start to goal on the true map; whether its heading check calls for the
search with the rectangle grown by the search's own amount and by less (could the trigger be looser than the
search?); then the SE(2) search run in slices: set-up time, slowest slice, slices, states, states per second
(process CPU time, so other load on the machine does not count).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
from clutter_suite import make_selected

from nav2_wrapper.core.costmap import Costmap, CostmapConfig
from nav2_wrapper.core.footprint import Footprint
from nav2_wrapper.core.headings import HeadingConfig, headings_over, resample
from nav2_wrapper.core.planner import GlobalPlanner
from nav2_wrapper.core.se2_planner import Se2Plan, Se2Planner, Se2PlannerConfig
from robonix_common.grid import GridMap
from robonix_eval.clutter import ClutterWorld, rasterize

RES = 0.05
FOOTPRINT = Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))


class _GrownBy(Se2Planner):
    """The collision grids with the rectangle grown by a fixed amount (the trigger experiment)."""

    def __init__(self, grow: float) -> None:
        super().__init__(Se2PlannerConfig(), FOOTPRINT)
        self._grow = grow

    def grow(self, res: float) -> float:
        return self._grow


def _triggers(cm: Costmap, path: np.ndarray, grow: float) -> bool:
    """Whether the heading check of the 2D path, on the rectangle grown by ``grow``, calls for the search."""
    pts = resample(path, 0.05)
    return not headings_over(pts, _GrownBy(grow).feasible_bins(cm, pts), HeadingConfig(bins=36, spacing=0.05)).feasible


def one(world: ClutterWorld, slice_states: int) -> dict:
    s = world.spec
    bounds = (-s.wall, -s.wall, s.width + s.wall, s.top)
    occ = rasterize(world.post_rects + world.wall_rects, bounds, RES)
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    cm.set_static_map(GridMap(np.where(occ, 100, 0).astype(np.int8), RES, bounds[0], bounds[1]))
    gp = GlobalPlanner()
    res = gp.plan(cm, s.start[:2], s.goal[:2])
    planner = Se2Planner(Se2PlannerConfig(), FOOTPRINT)
    triggers = {f"{g:.3f}": _triggers(cm, res.path, g) for g in (planner.grow(RES), 0.04, 0.03, 0.02, 0.01, 0.0)}
    t0 = time.process_time()
    search = planner.begin(cm, s.start, s.goal[:2], gp.traversal_table(), gp.cfg.tolerance, guide=res.path)
    setup = time.process_time() - t0
    if isinstance(search, Se2Plan):
        return {"world": world.seed, "setup_s": setup, "ok": False, "reason": search.reason, "triggers": triggers}
    slices: list[float] = []
    out = None
    while out is None:
        t = time.process_time()
        out = search.advance(slice_states)
        slices.append(time.process_time() - t)
    return {"world": world.seed, "ok": out.ok, "setup_s": setup, "slices": len(slices), "slice_max_s": max(slices),
            "states": out.expansions, "search_s": sum(slices),
            "triggers": triggers, "states_per_s": out.expansions / max(sum(slices), 1e-9)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="41,74,94")
    ap.add_argument("--slice", type=int, default=Se2PlannerConfig().tick_expansions)
    ap.add_argument("--out", default="bench/results/se2_slices.json")
    a = ap.parse_args()
    worlds = make_selected([int(v) for v in a.only.split(",")], 0.05)
    one(worlds[0], a.slice)                                        # compile / load the kernels
    rows = [one(w, a.slice) for w in worlds]
    for r in rows:
        print(f"clutter_{r['world']}: the heading check triggers the search at grow (m) "
              + ", ".join(f"{g}: {'yes' if t else 'no'}" for g, t in r["triggers"].items()))
        if "slices" in r:
            print(f"clutter_{r['world']}: set-up {r['setup_s'] * 1000:.0f} ms, {r['slices']} slices of "
                  f"{a.slice}, slowest {r['slice_max_s'] * 1000:.0f} ms, {r['states']} states "
                  f"({r['states_per_s'] / 1e6:.2f} M/s), found={r['ok']}")
        else:
            print(f"clutter_{r['world']}: no search ({r['reason']}), set-up {r['setup_s'] * 1000:.0f} ms")
    searched = [r for r in rows if "states_per_s" in r]
    if searched:
        rate = sum(r["states"] for r in searched) / sum(r["states"] / r["states_per_s"] for r in searched)
        print(f"overall {rate / 1e6:.2f} M states per CPU second -> a 150 ms slice is ~{int(0.15 * rate):,} states; "
              f"set-up median {statistics.median(r['setup_s'] for r in rows) * 1000:.0f} ms")
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"args": vars(a), "rows": rows}, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
