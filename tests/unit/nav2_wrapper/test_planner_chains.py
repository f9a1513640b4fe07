"""The chained cost-optimal kernel (uniform cost-0 cells expanded by scans, ``_chain``) returns the same cost as the
plain bucket kernel and as an independent Dijkstra, and a full 8-connected cell path that costs what it reports.

Maps are chosen to exercise the scans: large open (uniform) regions, narrow gaps between walls, goals inside
and outside uniform regions, starts on a cost band and inside the inscribed band (the escape disc).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nav2_wrapper.core import INSCRIBED, Costmap, CostmapConfig, GlobalPlanner, PlannerConfig
from nav2_wrapper.core import planner as planner_module
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

from .test_planner_speed_equivalence import centre, reference_cost

RES = 0.05
FP = load_footprint()


def open_costmap(rng: np.random.Generator, rows: int, cols: int, boxes: int, walls: int) -> Costmap:
    """Mostly open space (big uniform cost-0 regions) with a few boxes and walls that have narrow gaps."""
    grid = np.zeros((rows, cols), np.int8)
    for _ in range(boxes):
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        h, w = rng.integers(1, 8, 2)
        grid[r:r + h, c:c + w] = 100
    for _ in range(walls):
        if rng.random() < 0.5:
            c = int(rng.integers(5, cols - 5))
            grid[:, c:c + 2] = 100
            gap = int(rng.integers(2, rows - 20))
            grid[gap:gap + int(rng.integers(12, 18)), c:c + 2] = 0     # 1-7 cells passable past the bands
        else:
            r = int(rng.integers(5, rows - 5))
            grid[r:r + 2, :] = 100
            gap = int(rng.integers(2, cols - 20))
            grid[r:r + 2, gap:gap + int(rng.integers(12, 18))] = 0
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.45, cost_scaling_factor=3.0,
                               track_unknown_space=True, footprint=FP))
    cm.set_static_map(GridMap(grid, RES))
    return cm


def uniform_cells(costs: np.ndarray) -> np.ndarray:
    """(row, col) of cells whose whole 3×3 block is cost 0."""
    z = costs == 0
    u = np.zeros_like(z)
    u[1:-1, 1:-1] = np.logical_and.reduce([z[1 + dr:z.shape[0] - 1 + dr, 1 + dc:z.shape[1] - 1 + dc]
                                           for dr in (-1, 0, 1) for dc in (-1, 0, 1)])
    return np.argwhere(u)


def cell_path_cost(costs: np.ndarray, table: np.ndarray, cells: np.ndarray, start: tuple[int, int],
                   esc_r2: float, esc_cost: float) -> float:
    """Cost of a cell path in the planner's model (entered cell's factor × step length; blocked cells within the
    escape disc at ``esc_cost``), asserting every step is one 8-connected move."""
    total = 0.0
    for (r0, c0), (r1, c1) in zip(cells[:-1], cells[1:], strict=True):
        assert max(abs(r1 - r0), abs(c1 - c0)) == 1, ((r0, c0), (r1, c1))
        f = table[costs[r1, c1]]
        if not math.isfinite(f):
            assert (r1 - start[0]) ** 2 + (c1 - start[1]) ** 2 <= esc_r2
            f = esc_cost
        total += f * (math.sqrt(2.0) if r1 != r0 and c1 != c0 else 1.0)
    return total


@pytest.mark.parametrize(("seed", "boxes", "walls", "multiplier"),
                         [(30, 4, 2, 2.0), (31, 10, 1, 2.0), (32, 0, 3, 2.0), (33, 6, 2, 0.0), (34, 2, 0, 5.0)])
def test_chained_kernel_equals_bucket_kernel_and_dijkstra(seed: int, boxes: int, walls: int,
                                                          multiplier: float) -> None:
    rng = np.random.default_rng(seed)
    cm = open_costmap(rng, 60, 90, boxes, walls)
    cfg = PlannerConfig(heuristic_weight=1.0, cost_travel_multiplier=multiplier, smooth_path=False)
    planner = GlobalPlanner(cfg)
    table = planner.traversal_table()
    esc_r2 = (cfg.escape_radius / RES) ** 2
    esc_cost = 1.0 + multiplier * 2.0
    rows, cols = cm.costs.shape
    free = np.argwhere(cm.costs < INSCRIBED)
    uniform = uniform_cells(cm.costs)
    band = np.argwhere((cm.costs > 0) & (cm.costs < INSCRIBED))
    inscribed = np.argwhere(cm.costs == INSCRIBED)
    assert len(uniform) > 0.15 * rows * cols
    assert len(band)
    assert len(inscribed)
    checked = scanned = 0
    for k in range(36):
        starts = (uniform, band, inscribed, free)[k % 4]
        goals = (uniform, free, uniform, band)[(k // 4) % 4]     # goals inside and outside uniform regions
        a, b = starts[rng.integers(len(starts))], goals[rng.integers(len(goals))]
        sa, sb = (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))
        want = reference_cost(cm.costs, table, sa, sb, esc_r2, esc_cost)
        if not math.isfinite(want):
            continue
        planner.kernel = "buckets"
        plain = planner.plan(cm, centre(cm, a), centre(cm, b))
        planner.kernel = "chains"
        got = planner.plan(cm, centre(cm, a), centre(cm, b))
        scanned += planner.scanned
        assert plain.ok, plain.reason
        assert got.ok, got.reason
        assert got.cost == pytest.approx(want, rel=1e-5, abs=1e-4), (seed, sa, sb)
        assert got.cost == pytest.approx(plain.cost, rel=1e-5, abs=1e-4), (seed, sa, sb)
        # the full cell path the chained search recovers (scanned cells included) costs what it reports
        search = planner_module._Search(cm.costs, table, sa[0] * cols + sa[1], planner._rec, cfg.escape_radius / RES,
                                        esc_cost)
        cells, gvals = search.forward_path(planner._stamp, sb[0] * cols + sb[1])
        path = np.stack([cells // cols, cells % cols], axis=1)
        assert tuple(path[0]) == sa
        assert tuple(path[-1]) == sb
        assert cell_path_cost(cm.costs, table, path, sa, esc_r2, esc_cost) == pytest.approx(got.cost, rel=1e-5)
        assert np.all(np.diff(gvals) > 0)
        checked += 1
    assert checked >= 12, checked
    assert scanned > 0          # the scans ran (the maps have uniform regions), so they are what was checked


def test_chained_kernel_failure_closes_the_start_component() -> None:
    """An unreachable goal: the chained search's failure state is the bucket kernel's (every cell reachable from
    the start closed, scanned ones included), so the tolerance fallback finds the same cells."""
    grid = np.zeros((40, 80), np.int8)
    grid[:, 40:44] = 100
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.30, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(GridMap(grid, RES))
    results = {}
    for kernel in ("chains", "buckets"):
        planner = GlobalPlanner(PlannerConfig(heuristic_weight=1.0, tolerance=0.4))
        planner.kernel = kernel
        r = planner.plan(cm, (0.3, 1.0), (3.5, 1.0))
        assert not r.ok
        assert "not reachable" in r.reason
        stamp = planner._stamp
        st = planner._rec[0::2]
        results[kernel] = (st >> planner_module._search.STATE_SHIFT == stamp) & (st & 1 == 1)
        ok = planner.plan(cm, (0.3, 1.0), (1.85, 1.0))         # blocked goal, free cells within tolerance
        assert ok.ok, ok.reason
    np.testing.assert_array_equal(results["chains"], results["buckets"])
