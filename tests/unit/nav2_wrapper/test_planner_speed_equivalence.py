"""The cost-optimal planner (heuristic_weight 1.0) returns exactly the cheapest path: its cost equals the
reference planner's (a textbook A*, ``nav2_wrapper.core.reference``) and its grid path costs what it reports,
on small random maps, including starts inside the inscribed band
(the escape disc), blocked goals (tolerance), unreachable goals and unknown regions. Its kernel is tuned for
speed (bucket queue, stamped records, path recovered from g, moves pruned), so this is the check that none
of that changed the answer.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nav2_wrapper.core import INSCRIBED, Costmap, CostmapConfig, GlobalPlanner, PlannerConfig, _search
from nav2_wrapper.core import planner as planner_module
from nav2_wrapper.core.costs import LETHAL, MAX_NON_OBSTACLE, NO_INFORMATION
from nav2_wrapper.core.reference import path_cost, reference_plan
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

RES = 0.05
FP = load_footprint()


def random_costmap(rng: np.random.Generator, rows: int = 48, cols: int = 64, boxes: int = 10) -> Costmap:
    grid = np.zeros((rows, cols), np.int8)
    for _ in range(boxes):
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        h, w = rng.integers(1, 6, 2)
        grid[r:r + h, c:c + w] = 100
    grid[rng.random((rows, cols)) < 0.01] = -1          # a few unknown cells
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.30, cost_scaling_factor=3.0,
                               track_unknown_space=True, footprint=FP))
    cm.set_static_map(GridMap(grid, RES))
    return cm


def reference_cost(costs: np.ndarray, table: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
                   esc_r2: float, esc_cost: float) -> float:
    """The product's reference planner (plain A*, ``nav2_wrapper.core.reference``): the cheapest cost."""
    return reference_plan(costs, table, start, goal, esc_r2, esc_cost).cost


def assert_path_costs(cm: Costmap, planner: GlobalPlanner, got, start: np.ndarray) -> None:
    """The planner's grid path (before shortcutting) is a legal 8-connected path whose cost is the reported one."""
    cfg = planner.cfg
    cells = got.cells
    assert tuple(cells[0]) == (int(start[0]), int(start[1]))
    cost = path_cost(cm.costs, planner.traversal_table(), cells, (cfg.escape_radius / RES) ** 2,
                     1.0 + cfg.cost_travel_multiplier * 2.0)
    assert cost == pytest.approx(got.cost, rel=1e-5, abs=1e-4)


def centre(cm: Costmap, cell: np.ndarray) -> tuple[float, float]:
    x, y = cm.cell_to_world(cell[1], cell[0])
    return float(x), float(y)


@pytest.mark.parametrize(("seed", "multiplier", "boxes"), [(s, 2.0, 10) for s in range(6)]
                         + [(s, 0.0, 3) for s in range(6, 9)] + [(s, 2.0, 2) for s in range(9, 11)])
def test_cost_equals_plain_dijkstra_on_random_maps(seed: int, multiplier: float, boxes: int) -> None:
    """Cluttered maps, and open ones (multiplier 0: every free cell costs 1, so equal-cost paths abound and
    the kernel's pruning of moves with an equally cheap canonical alternative is exercised hardest)."""
    rng = np.random.default_rng(seed)
    cm = random_costmap(rng, boxes=boxes)
    cfg = PlannerConfig(heuristic_weight=1.0, smooth_path=seed % 2 == 0, cost_travel_multiplier=multiplier)
    planner = GlobalPlanner(cfg)
    table = planner.traversal_table()
    esc_r2 = (cfg.escape_radius / RES) ** 2
    esc_cost = 1.0 + cfg.cost_travel_multiplier * 2.0
    free = np.argwhere(cm.costs < INSCRIBED)
    band = np.argwhere(cm.costs == INSCRIBED)
    checked = unreachable = 0
    for k in range(25):
        a = (band if k % 5 == 0 and len(band) else free)[rng.integers(len(band) if k % 5 == 0 and len(band)
                                                                      else len(free))]
        b = free[rng.integers(len(free))]
        want = reference_cost(cm.costs, table, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), esc_r2, esc_cost)
        got = planner.plan(cm, centre(cm, a), centre(cm, b))
        if not math.isfinite(want):
            unreachable += 1
            continue          # an unreachable free goal may still be met within tolerance: not compared here
        assert got.ok, got.reason
        assert got.cost == pytest.approx(want, rel=1e-5, abs=1e-4), (seed, k, tuple(a), tuple(b))
        assert_path_costs(cm, planner, got, a)
        checked += 1
    assert checked >= 15, (checked, unreachable)


def blob_costmap(rng: np.random.Generator, rows: int = 56, cols: int = 72) -> Costmap:
    """Boxes plus whole unknown regions (not single cells), so cheapest paths weigh crossing unknown space
    against detours through free space and the cost bands, and f plateaus end at the goal in mixed terrain."""
    grid = np.zeros((rows, cols), np.int8)
    for _ in range(4):
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        h, w = rng.integers(4, 16, 2)
        grid[r:r + h, c:c + w] = -1
    for _ in range(8):
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        h, w = rng.integers(1, 7, 2)
        grid[r:r + h, c:c + w] = 100
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.35, cost_scaling_factor=2.0,
                               track_unknown_space=True, footprint=FP))
    cm.set_static_map(GridMap(grid, RES))
    return cm


@pytest.mark.parametrize(("seed", "multiplier", "unknown_cost"),
                         [(20, 2.0, 0), (21, 2.0, 120), (22, 5.0, 252), (23, 0.5, 60), (24, 3.0, 200),
                          (25, 1.0, 30)])
def test_cost_equals_plain_dijkstra_with_unknown_regions(seed: int, multiplier: float, unknown_cost: int) -> None:
    """Unknown regions charged from free (0) to the most a non-obstacle cell costs (252), several cost scales.

    The bucket search's stop is only right if the heuristic is a true lower bound and the goal's bucket is
    emptied first: stopping as soon as the goal is closed gives a dearer path on one of these maps and
    fails here (tried), as did a 3 % larger heuristic on an earlier variant of the kernel."""
    rng = np.random.default_rng(seed)
    cm = blob_costmap(rng)
    cfg = PlannerConfig(heuristic_weight=1.0, cost_travel_multiplier=multiplier, unknown_cost=unknown_cost,
                        smooth_path=False)
    planner = GlobalPlanner(cfg)
    table = planner.traversal_table()
    esc_r2 = (cfg.escape_radius / RES) ** 2
    esc_cost = 1.0 + multiplier * 2.0
    free = np.argwhere(cm.costs < INSCRIBED)
    checked = 0
    for _ in range(30):
        a, b = free[rng.integers(len(free))], free[rng.integers(len(free))]
        want = reference_cost(cm.costs, table, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), esc_r2, esc_cost)
        if not math.isfinite(want):
            continue
        got = planner.plan(cm, centre(cm, a), centre(cm, b))
        assert got.ok, got.reason
        assert got.cost == pytest.approx(want, rel=1e-5, abs=1e-4), (seed, tuple(a), tuple(b))
        checked += 1
    assert checked >= 20, checked


def test_same_cost_on_repeated_plans_with_reused_buffers() -> None:
    """Stamped records are reused without clearing: a plan after many others gives the same cost."""
    rng = np.random.default_rng(11)
    cm = random_costmap(rng, boxes=6)
    free = np.argwhere(cm.costs < INSCRIBED)
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=1.0))
    a, b = free[0], free[-1]
    first = planner.plan(cm, centre(cm, a), centre(cm, b))
    for _ in range(30):
        planner.plan(cm, centre(cm, free[rng.integers(len(free))]), centre(cm, free[rng.integers(len(free))]))
    again = planner.plan(cm, centre(cm, a), centre(cm, b))
    assert first.ok == again.ok
    assert again.cost == pytest.approx(first.cost, rel=1e-9)
    np.testing.assert_allclose(again.path, first.path)


@pytest.mark.parametrize("weight", [1.0, 1.25])
def test_stamp_wraparound_keeps_costs_exact(weight: float) -> None:
    """A record's state word packs the plan's stamp above the arrival move and the closed bit; when the stamp
    nears the int32 limit the buffer is cleared and stamps restart. Plans on both sides of that wrap (both
    kernels) cost what plain Dijkstra says, and the failure path still finds the start's closed cells."""
    rng = np.random.default_rng(23)
    cm = random_costmap(rng, boxes=8)
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=weight))
    table = planner.traversal_table()
    free = np.argwhere(cm.costs < INSCRIBED)
    pairs = [(free[rng.integers(len(free))], free[rng.integers(len(free))]) for _ in range(6)]
    planner.plan(cm, centre(cm, pairs[0][0]), centre(cm, pairs[0][1]))
    planner._stamp = 2 ** (31 - _search.STATE_SHIFT) - 4        # three plans before the wrap
    for a, b in pairs:
        got = planner.plan(cm, centre(cm, a), centre(cm, b))
        want = reference_cost(cm.costs, table, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), 49.0, 5.0)
        assert got.ok, got.reason
        if weight == 1.0:
            assert got.cost == pytest.approx(want, rel=1e-5, abs=1e-4)
        else:
            assert want - 1e-4 <= got.cost <= weight * want + 1e-4
        assert int(planner._rec.min()) >= 0          # the packed state never overflowed int32
    assert planner._stamp < 8, planner._stamp        # the wrap happened


@pytest.mark.parametrize("shape", [(1, 60), (60, 1), (2, 40), (3, 3)])
def test_one_and_two_row_maps(shape: tuple[int, int]) -> None:
    """Maps with no interior cell (every cell on the edge) or a tiny one: the kernel's edge path only."""
    rows, cols = shape
    costs = np.zeros((rows, cols), np.uint8)
    costs.flat[::7] = 120
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FP))
    cm.set_static_map(GridMap(np.zeros((rows, cols), np.int8), RES))
    cm.costs[:] = costs
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=1.0))
    table = planner.traversal_table()
    cells = [(0, 0), (rows - 1, cols - 1), (rows // 2, cols // 2), (0, cols - 1), (rows - 1, 0)]
    for a in cells:
        for b in cells:
            want = reference_cost(cm.costs, table, a, b, 49.0, 5.0)
            got = planner.plan(cm, centre(cm, np.array(a)), centre(cm, np.array(b)))
            assert got.ok, got.reason
            assert got.cost == pytest.approx(want, rel=1e-5, abs=1e-4), (shape, a, b)


def test_unreachable_goal_fails_with_reason_and_blocked_goal_uses_tolerance() -> None:
    grid = np.zeros((40, 60), np.int8)
    grid[:, 30:34] = 100                      # a wall splits the map
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.30, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(GridMap(grid, RES))
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=1.0, tolerance=0.2))
    r = planner.plan(cm, (0.3, 1.0), (2.8, 1.0))
    assert not r.ok
    assert "not reachable" in r.reason
    r = planner.plan(cm, (0.3, 1.0), (1.35, 1.0))   # in the wall's inscribed band, free cells within 0.2 m
    assert r.ok, r.reason
    assert cm.cost_at(r.path[-1:, 0], r.path[-1:, 1])[0] < INSCRIBED


def test_start_equals_goal_and_starts_on_the_map_edge() -> None:
    rng = np.random.default_rng(5)
    cm = random_costmap(rng, boxes=4)
    planner = GlobalPlanner(PlannerConfig(heuristic_weight=1.0))
    free = np.argwhere(cm.costs < INSCRIBED)
    a = free[len(free) // 2]
    r = planner.plan(cm, centre(cm, a), centre(cm, a))
    assert r.ok, r.reason
    assert r.cost == 0.0
    edge = free[(free[:, 0] == 0) | (free[:, 1] == 0)]
    assert len(edge), "no free cell on the map edge"
    table = planner.traversal_table()
    for e in edge[:: max(1, len(edge) // 4)]:
        want = reference_cost(cm.costs, table, (int(e[0]), int(e[1])), (int(a[0]), int(a[1])), 49.0, 5.0)
        if math.isfinite(want):       # (an unreachable goal may still be met within tolerance)
            got = planner.plan(cm, centre(cm, e), centre(cm, a))
            assert got.ok, got.reason
            assert got.cost == pytest.approx(want, rel=1e-5)


def random_cost_field(rng: np.random.Generator, rows: int = 40, cols: int = 56) -> Costmap:
    """A costmap whose master costs are set directly: patches of random graded cost, blocked patches
    (inscribed and lethal), unknown patches, thin blocked walls with diagonal gaps, and per-cell noise. No
    inflation structure, so the kernel's weight-dependent move pruning meets cost steps in every direction."""
    costs = np.zeros((rows, cols), np.uint8)
    for _ in range(12):
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        h, w = rng.integers(2, 12, 2)
        costs[r:r + h, c:c + w] = rng.integers(1, MAX_NON_OBSTACLE + 1)
    noisy = rng.random((rows, cols)) < 0.15
    costs[noisy] = rng.integers(0, MAX_NON_OBSTACLE + 1, int(noisy.sum()))
    for value in (NO_INFORMATION, NO_INFORMATION, INSCRIBED, LETHAL, LETHAL):
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        h, w = rng.integers(1, 8, 2)
        costs[r:r + h, c:c + w] = value
    for _ in range(3):            # staircase walls: blocked cells touching only at corners (no squeeze through)
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        for k in range(int(rng.integers(4, 15))):
            if r + k < rows and c + k < cols:
                costs[r + k, c + k] = LETHAL
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FP))
    cm.set_static_map(GridMap(np.zeros((rows, cols), np.int8), RES))
    cm.costs[:] = costs
    return cm


FIELD_CASES = [(30, 2.0, 200, True), (31, 0.0, 0, True), (32, 5.0, 252, True), (33, 1.0, 40, True),
               (34, 3.0, 120, False), (35, 0.3, 252, True), (36, 2.0, 0, True), (37, 8.0, 100, False)]


def field_pairs(cm: Costmap, table: np.ndarray, rng: np.random.Generator, n: int) -> list[tuple[np.ndarray, ...]]:
    """n (start, goal) cells: goals traversable, starts traversable or (every 4th) in the inscribed band."""
    ok = np.argwhere(np.isfinite(table[cm.costs]))
    band = np.argwhere(cm.costs == INSCRIBED)
    pairs = []
    for k in range(n):
        pool = band if k % 4 == 0 and len(band) else ok
        pairs.append((pool[rng.integers(len(pool))], ok[rng.integers(len(ok))]))
    return pairs


def field_mismatches(cfg: PlannerConfig, seed: int, check_paths: bool = True) -> tuple[int, int]:
    """(pairs compared, pairs whose planned cost differs from plain Dijkstra) on one random cost field."""
    rng = np.random.default_rng(seed)
    cm = random_cost_field(rng)
    planner = GlobalPlanner(cfg)
    table = planner.traversal_table()
    esc_r2 = (cfg.escape_radius / RES) ** 2
    esc_cost = 1.0 + cfg.cost_travel_multiplier * 2.0
    checked = wrong = 0
    for a, b in field_pairs(cm, table, rng, 40):
        want = reference_cost(cm.costs, table, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), esc_r2, esc_cost)
        if not math.isfinite(want):
            continue
        got = planner.plan(cm, centre(cm, a), centre(cm, b))
        assert got.ok, got.reason
        if check_paths:
            assert_path_costs(cm, planner, got, a)
        checked += 1
        wrong += got.cost != pytest.approx(want, rel=1e-5, abs=1e-4)
    return checked, wrong


@pytest.mark.parametrize(("seed", "multiplier", "unknown_cost", "smooth"), FIELD_CASES)
def test_cost_equals_plain_dijkstra_on_random_cost_fields(seed: int, multiplier: float, unknown_cost: int,
                                                         smooth: bool) -> None:
    """Arbitrary graded costs (not the smooth inflation profile), unknown patches from free to the dearest
    charge, diagonal-only walls, starts in the inscribed band: 40 pairs per field, every cost exact."""
    cfg = PlannerConfig(heuristic_weight=1.0, cost_travel_multiplier=multiplier, unknown_cost=unknown_cost,
                        smooth_path=smooth)
    checked, wrong = field_mismatches(cfg, seed)
    assert checked >= 25, checked
    assert wrong == 0, (seed, wrong, checked)


def test_the_comparison_catches_an_overestimating_heuristic(monkeypatch: pytest.MonkeyPatch) -> None:
    """The check above has teeth: the same kernel with the heuristic 15 % too large (inadmissible) returns a
    dearer path on some of these pairs, and the comparison reports it."""

    kernel = planner_module._search.astar

    def inflated(costs, table, start, goal, rec, stamp, esc_r2, esc_cost, weight, h_scale, *rest):
        return kernel(costs, table, start, goal, rec, stamp, esc_r2, esc_cost, weight, h_scale * 1.15, *rest)

    monkeypatch.setattr(planner_module._search, "astar", inflated)
    wrong = 0
    for seed, multiplier, unknown_cost, _ in FIELD_CASES[:4]:
        cfg = PlannerConfig(heuristic_weight=1.0, cost_travel_multiplier=multiplier, unknown_cost=unknown_cost)
        wrong += field_mismatches(cfg, seed, check_paths=False)[1]
    assert wrong > 0


@pytest.mark.parametrize(("start", "goal"), [((0.5, 0.5), (8.0, 5.5)), ((9.5, 0.5), (0.5, 9.0)),
                                             ((1.0, 5.0), (9.0, 5.2))])
def test_open_space_search_runs_down_the_equal_f_plateau(start: tuple[float, float],
                                                          goal: tuple[float, float]) -> None:
    """On an empty map the octile h is exact, so every cell of the start-goal parallelogram has f = C*: the
    kernel's tie-break (LIFO in narrow buckets, cells whose f reaches the goal's g not expanded) must head
    straight for the goal, not sweep the plateau (the FIFO kernel expanded 785-5151 cells on these)."""
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FP))
    cm.set_static_map(GridMap(np.zeros((200, 200), np.int8), RES))
    r = GlobalPlanner(PlannerConfig(heuristic_weight=1.0)).plan(cm, start, goal)
    assert r.ok, r.reason
    sc, sr = (int(v) for v in cm.world_to_cell(*start))
    gc, gr = (int(v) for v in cm.world_to_cell(*goal))
    dc, dr = abs(gc - sc), abs(gr - sr)
    assert r.cost == pytest.approx(max(dc, dr) + (math.sqrt(2.0) - 1.0) * min(dc, dr), rel=1e-5)
    assert r.expansions <= 2 * (max(dc, dr) + 1), r.expansions
