"""How long one control tick stalls for the SE(2) fallback: set-up (window, collision grids, heuristic) and a
slice of ``tick_expansions`` states, on the fully known clutter worlds whose 2D path has no fitting heading.

    python bench/se2_slices.py [--only 41,74,94] [--slice 60000] [--out bench/results/se2_slices.json]

For each world: the 2D plan from start to goal on the true map, the heading check, then the SE(2) search run
in slices; prints the set-up time, the slowest slice, the number of slices and states, and the states per
second (process CPU time, so other load on the machine does not count).
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
from nav2_wrapper.core.planner import GlobalPlanner
from nav2_wrapper.core.se2_planner import Se2Plan, Se2Planner, Se2PlannerConfig
from robonix_common.grid import GridMap
from robonix_eval.clutter import ClutterWorld, rasterize

RES = 0.05
FOOTPRINT = Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))


def one(world: ClutterWorld, slice_states: int) -> dict:
    s = world.spec
    bounds = (-s.wall, -s.wall, s.width + s.wall, s.top)
    occ = rasterize(world.post_rects + world.wall_rects, bounds, RES)
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    cm.set_static_map(GridMap(np.where(occ, 100, 0).astype(np.int8), RES, bounds[0], bounds[1]))
    gp = GlobalPlanner()
    res = gp.plan(cm, s.start[:2], s.goal[:2])
    planner = Se2Planner(Se2PlannerConfig(), FOOTPRINT)
    t0 = time.process_time()
    search = planner.begin(cm, s.start, s.goal[:2], gp.traversal_table(), gp.cfg.tolerance, guide=res.path)
    setup = time.process_time() - t0
    if isinstance(search, Se2Plan):
        return {"world": world.seed, "setup_s": setup, "ok": False, "reason": search.reason}
    slices: list[float] = []
    out = None
    while out is None:
        t = time.process_time()
        out = search.advance(slice_states)
        slices.append(time.process_time() - t)
    return {"world": world.seed, "ok": out.ok, "setup_s": setup, "slices": len(slices), "slice_max_s": max(slices),
            "states": out.expansions, "search_s": sum(slices), "states_per_s": out.expansions / max(sum(slices), 1e-9)}


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
