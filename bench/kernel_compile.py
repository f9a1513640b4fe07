"""Cold and warm numba cost of each kernel family: what a fresh checkout, a fresh wheel install or an image build
pays before its first plan, and what every later process pays to load the cached machine code.

    python bench/kernel_compile.py [--kernels first_plan planner se2 mppi slam warmup]

Why: a cold compile is paid once per install, but the test suite makes three installs (the checkout, the
wheel test's fresh virtualenv, the container image) and compiles the "buckets" kernel once more for the
equivalence tests; the figures here say how much of the suite's wall time that is. Each kernel family runs in
a fresh interpreter on its own empty ``NUMBA_CACHE_DIR`` (cold: compile and write the cache), then in a second
interpreter on the same directory (warm: load). The warm-up planning map of ``nav2_wrapper.core.warmup`` is
used; kernels are specialised by argument types only, so the figures hold for real maps. ``warmup`` is the
whole ``compile_kernels()`` of a navigation process; ``first_plan`` is a fresh interpreter's import of
the planner plus its first plan on a 20 m × 20 m map (400×400 cells, random boxes), imports included.
The load average is printed beside the figures: on a shared machine they include the neighbours' CPU use.
Writes bench/results/kernel_compile.json.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "bench" / "results" / "kernel_compile.json"
KERNELS = ("first_plan", "planner", "se2", "mppi", "slam", "warmup")
T_START = time.perf_counter()


def _planner_setup() -> tuple[Any, Any]:
    """The warm-up's map (a wall with the path bending round it) and its square footprint."""
    import numpy as np

    from nav2_wrapper.core.costmap import Costmap, CostmapConfig
    from nav2_wrapper.core.footprint import Footprint
    from robonix_common.grid import GridMap

    grid = np.zeros((60, 60), np.int8)
    grid[10:50, 28:32] = 100
    square = Footprint(np.array([[0.3, 0.25], [-0.3, 0.25], [-0.3, -0.25], [0.3, -0.25]]))
    costmap = Costmap(CostmapConfig(obstacle_layer=False, footprint=square))
    costmap.set_static_map(GridMap(grid, 0.05))
    return costmap, square


def _plan(costmap: Any, start: tuple[float, float], goal: tuple[float, float]) -> None:
    from nav2_wrapper.core.planner import GlobalPlanner, PlannerConfig

    result = GlobalPlanner(PlannerConfig()).plan(costmap, start, goal)
    if not result.ok:
        raise RuntimeError(f"plan failed: {result.reason}")


def _first_plan() -> float:
    """Seconds from this interpreter's start to the end of its first plan on a 20 m × 20 m map."""
    import numpy as np

    from nav2_wrapper.core.costmap import Costmap, CostmapConfig
    from nav2_wrapper.robot_io import load_footprint
    from robonix_common.grid import GridMap

    rng = np.random.default_rng(0)
    grid = np.zeros((400, 400), np.int8)
    for _ in range(120):
        (r, c), (h, w) = rng.integers(0, 400, 2), rng.integers(4, 30, 2)
        grid[r:r + h, c:c + w] = 100
    grid[:40, :40] = grid[-40:, -40:] = 0
    costmap = Costmap(CostmapConfig(obstacle_layer=False, footprint=load_footprint()))
    costmap.set_static_map(GridMap(grid, 0.05))
    _plan(costmap, (1.0, 1.0), (19.0, 19.0))
    return time.perf_counter() - T_START


def _run_one(kernel: str) -> float:
    """Seconds this interpreter spends compiling (or loading) ``kernel``; imports and the costmap come first
    (``first_plan``: everything from the interpreter's start)."""
    if kernel == "first_plan":
        return _first_plan()
    import nav2_wrapper.core.planner  # noqa: F401 - imported before timing: only numba's work is timed
    from nav2_wrapper.core import warmup

    costmap, square = _planner_setup()
    steps = {
        "planner": lambda: _plan(costmap, (0.4, 1.5), (2.6, 1.5)),
        "se2": lambda: warmup._compile_se2(costmap, square),
        "mppi": warmup._compile_mppi,
        "slam": _slam,
        "warmup": warmup.compile_kernels,
    }
    t0 = time.perf_counter()
    steps[kernel]()
    return time.perf_counter() - t0


def _slam() -> None:
    from slam_service.core import kernels

    kernels.load()


def _child(kernel: str, cache: str) -> tuple[float, float]:
    """(seconds the child reports, CPU seconds of the whole child process: a loaded machine inflates the first
    far more than the second)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    r = subprocess.run([sys.executable, __file__, "--child", kernel], env=env, capture_output=True, text=True,
                       timeout=1800, cwd=ROOT)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        raise RuntimeError(f"{kernel}: child exited {r.returncode}: {r.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return float(r.stdout.strip().splitlines()[-1]), cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kernels", nargs="+", choices=KERNELS, default=list(KERNELS))
    ap.add_argument("--child", choices=KERNELS, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(f"{_run_one(args.child):.3f}", flush=True)
        return
    import numba

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    results: dict[str, Any] = {"commit": commit.strip(), "numba": numba.__version__,
                               "load_avg_at_start": os.getloadavg()[0], "kernels": {}}
    print(f"{'kernel':10s} {'cold s':>8s} {'warm s':>8s} {'cold CPU s':>11s} {'warm CPU s':>11s}   "
          f"(load average {os.getloadavg()[0]:.2f}; CPU: the whole child process)")
    for kernel in args.kernels:
        with tempfile.TemporaryDirectory(prefix="kernel_compile_") as cache:
            cold, cold_cpu = _child(kernel, cache)
            warm, warm_cpu = _child(kernel, cache)
        results["kernels"][kernel] = {"cold_s": round(cold, 2), "warm_s": round(warm, 3),
                                      "cold_process_cpu_s": round(cold_cpu, 2),
                                      "warm_process_cpu_s": round(warm_cpu, 2)}
        print(f"{kernel:10s} {cold:8.1f} {warm:8.2f} {cold_cpu:11.1f} {warm_cpu:11.1f}", flush=True)
    results["load_avg_at_end"] = os.getloadavg()[0]
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(results, indent=1))
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    main()
