"""Controller step time: the MPPI controller beside the pursuit controller, on the same recorded states.

    python bench/controller_bench.py [--worlds 3] [--repeat 3] [--out bench/results/controller.json]

States (pose, velocity, goal, path, local costmap) are recorded while the in-process stack crosses
generated clutter worlds with the MPPI controller; then each controller's ``compute`` is timed on every
recorded state, ``--repeat`` times, in the same process. MPPI runs with its default sample count (Nav2's
1000 sequences × 56 steps). Prints median / p95 / max per controller; writes JSON.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from nav2_wrapper.core.controller import HolonomicController
from nav2_wrapper.core.mppi import MppiConfig, MppiController
from robonix_eval.clutter import generate
from robonix_eval.pipeline import Pipeline, PipelineOptions


def record(worlds: int, every: int = 5) -> list[tuple]:
    """Every ``every``-th control step of clutter crossings: the controller's inputs, deep-copied."""
    states: list[tuple] = []
    seed = 0
    while worlds:
        w = generate(seed, 0.25, survive=3)
        seed += 1
        if not w.passable:
            continue
        worlds -= 1
        pipe = Pipeline(PipelineOptions(scene=w.scene(), seed=0, controller="mppi"))
        ctl = pipe.nav.controller
        orig = ctl.compute
        count = [0]

        def spy(pose, vel, goal, costmap, dt, xy_reached=False, orig=orig, ctl=ctl, count=count):
            count[0] += 1
            if count[0] % every == 0 and len(ctl.path):
                states.append((pose, vel, goal, copy.deepcopy(costmap), dt, xy_reached, ctl.path.copy()))
            return orig(pose, vel, goal, costmap, dt, xy_reached)

        ctl.compute = spy
        pipe.run_for(0.5)
        g = w.spec.goal
        pipe.navigate(g[0], g[1], g[2], timeout=120)
    return states


def time_controller(ctl: HolonomicController, states: list[tuple], repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        for pose, vel, goal, costmap, dt, xy, path in states:
            ctl.set_path(path)
            t0 = time.perf_counter()
            ctl.compute(pose, vel, goal, costmap, dt, xy)
            out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--worlds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "controller.json"))
    a = ap.parse_args()
    if not (1 <= a.worlds <= 50 and 1 <= a.repeat <= 20):
        raise SystemExit("controller_bench: --worlds 1..50, --repeat 1..20")
    states = record(a.worlds)
    cfg = Pipeline(PipelineOptions(scene="apartment")).params.config.controller
    result = {}
    for name, ctl in (("pursuit", HolonomicController(cfg)), ("mppi", MppiController(cfg, MppiConfig()))):
        time_controller(ctl, states[:5], 1)            # warm caches and compiled kernels
        t = np.array(time_controller(ctl, states, a.repeat)) * 1e3
        result[name] = {"steps": len(t), "median_ms": float(np.median(t)), "p95_ms": float(np.percentile(t, 95)),
                        "max_ms": float(t.max())}
        print(f"{name:<8} {len(t):>5} steps  median {result[name]['median_ms']:6.2f} ms  "
              f"p95 {result[name]['p95_ms']:6.2f} ms  max {result[name]['max_ms']:6.2f} ms")
    result["mppi_over_pursuit_median"] = result["mppi"]["median_ms"] / result["pursuit"]["median_ms"]
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"bench": "controller", "states": len(states), "repeat": a.repeat,
                               "batch_size": MppiConfig().batch_size, "time_steps": MppiConfig().time_steps,
                               "machine": platform.machine(), "python": platform.python_version(),
                               "load_avg_at_end": list(os.getloadavg()),
                               "results": result},
                              indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
