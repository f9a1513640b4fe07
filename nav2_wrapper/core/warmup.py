"""Compile the planner's numba kernels ahead of time, into the on-disk cache (``NUMBA_CACHE_DIR``).

Why: a cold numba cache costs nav2 3-6 s of compiling in its first plan (CMD_INIT warm-up), which is
most of a cold boot. Running this once after install (the container image does it at build time)
leaves the compiled kernels where every later process loads them in milliseconds. Kernels are
specialised by argument types only, so planning on a tiny map compiles exactly what a real one uses.

    python -m nav2_wrapper.core.warmup        # prints how long it took and where the cache is
"""

from __future__ import annotations

import logging
import os
import threading
import time

import numpy as np

from robonix_common.grid import GridMap

from .costmap import Costmap, CostmapConfig
from .footprint import Footprint
from .planner import GlobalPlanner, PlannerConfig


def compile_kernels() -> float:
    """Plan once around an obstacle (A*, backtrack and the shortcut pass all run), once with the SE(2)
    fallback, and run the MPPI controller's rollout kernel; returns seconds."""
    t0 = time.perf_counter()
    grid = np.zeros((60, 60), np.int8)
    grid[10:50, 28:32] = 100  # a wall between start and goal, so the path bends and gets shortcut
    # Kernels are specialised by argument types only: any footprint compiles what the robot's plans use.
    square = Footprint(np.array([[0.3, 0.25], [-0.3, 0.25], [-0.3, -0.25], [0.3, -0.25]]))
    costmap = Costmap(CostmapConfig(obstacle_layer=False, footprint=square))
    costmap.set_static_map(GridMap(grid, 0.05))
    result = GlobalPlanner(PlannerConfig()).plan(costmap, (0.4, 1.5), (2.6, 1.5))   # every weight: one kernel
    if not result.ok:
        raise RuntimeError(f"warm-up plan failed: {result.reason}")
    _compile_se2(costmap, square)
    _compile_mppi()
    return time.perf_counter() - t0


def _compile_se2(costmap: Costmap, footprint: Footprint) -> None:
    """The footprint-aware fallback's kernels (collision grids, cost to go, lattice A*): the first plan that
    needs the fallback is usually mid-run, where 20 s of compiling would stall the robot."""
    from .se2_planner import Se2Planner, Se2PlannerConfig

    plan = Se2Planner(Se2PlannerConfig(), footprint).plan(costmap, (0.4, 1.5, 0.0), (2.6, 1.5),
                                                          GlobalPlanner().traversal_table())
    if not plan.ok:
        raise RuntimeError(f"warm-up SE(2) plan failed: {plan.reason}")


def _compile_mppi() -> None:
    """The MPPI controller's limit-and-rollout kernel, on the argument types a control step passes."""
    from ._mppi_kernels import limit_and_rollout

    u = np.zeros((2, 3, 3))
    v3 = np.zeros(3)
    limit_and_rollout(u, v3, v3, np.ones(3), np.ones(3), 0.05, np.empty_like(u))


_done = threading.Event()
_finished = threading.Event()  # set when the background compile ended, compiled or failed


def ready() -> bool:
    """The kernels are compiled or loaded in this process (a plan will not wait for numba)."""
    return _done.is_set()


def wait_finished(timeout: float) -> bool:
    """Wait up to ``timeout`` s for a background compile in progress; True when none is running.

    The navigation loop waits here *outside* its lock before a step, so a goal's first plan does not
    hold the lock for the seconds a cold compile takes and status/cancel calls stay answered.
    """
    if not _started:
        return True
    return _finished.wait(timeout)


_started: list[threading.Thread] = []
_start_lock = threading.Lock()


def compile_in_background() -> threading.Thread:
    """Start compiling (or loading from the cache) in a daemon thread, once per process.

    The provider calls this at its first CMD_INIT (answered ``Deferred`` until the map exists), not at
    process start: the upstream providers are starting then and need the CPU more. Compiling while
    it waits for its inputs takes the 0.2 s (cached) to 4 s (cold) off the boot's critical path.
    CMD_INIT's warm-up plan is skipped while this runs (``ready()``); a goal that needs a kernel before
    it is done simply waits on numba's compile lock.
    """

    def run() -> None:
        try:
            compile_kernels()
            _done.set()
        except Exception:
            logging.getLogger("nav2_wrapper").warning("background kernel compile failed", exc_info=True)
        finally:
            _finished.set()

    with _start_lock:
        if not _started:
            _started.append(threading.Thread(target=run, name="numba-warmup", daemon=True))
            _started[0].start()
        return _started[0]


def main() -> None:
    took = compile_kernels()
    where = os.environ.get("NUMBA_CACHE_DIR") or "numba's default (__pycache__ or the user cache)"
    print(f"numba kernels ready in {took:.2f} s (cache: {where})", flush=True)


if __name__ == "__main__":
    main()
