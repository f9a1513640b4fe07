"""Costmap layers: Nav2 cost values, inflation formula, marking/clearing, incremental static growth."""

import math

import numpy as np
import pytest

from nav2_wrapper.core import INSCRIBED, LETHAL, NO_INFORMATION, Costmap, CostmapConfig, Scan
from nav2_wrapper.core.costs import inflation_cost
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

FP = load_footprint()


def test_footprint_radii_from_robot_description():
    assert FP.inscribed_radius == pytest.approx(0.25)
    assert FP.circumscribed_radius == pytest.approx(math.hypot(0.35, 0.25))


def _single_obstacle(k=3.0, radius=1.0):
    g = np.zeros((81, 81), np.int8)
    g[40, 40] = 100
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=radius, cost_scaling_factor=k, footprint=FP))
    cm.set_static_map(GridMap(g, 0.05))
    return cm


@pytest.mark.parametrize("order", [1, -1])
def test_padded_footprint_moves_every_edge_out_by_the_margin(order: int) -> None:
    from nav2_wrapper.core.footprint import Footprint

    rect = np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]])[::order]
    grown = Footprint(rect).padded(0.05)
    assert np.allclose(np.abs(grown.polygon), [[0.40, 0.30]] * 4)
    assert grown.inscribed_radius == pytest.approx(0.30)
    # a pentagon: every edge of the grown one lies 0.05 m outside the matching edge of the original
    pent = Footprint(np.array([[0.4, 0.0], [0.1, 0.3], [-0.3, 0.2], [-0.3, -0.2], [0.1, -0.3]])[::order])
    big = pent.padded(0.05)
    for i in range(5):
        a, b = pent.polygon[i], pent.polygon[(i + 1) % 5]
        n = np.array([b[1] - a[1], a[0] - b[0]]) / math.hypot(*(b - a))
        n *= np.sign(np.dot(n, a - pent.polygon.mean(axis=0)))   # outward
        assert np.dot(big.polygon[i] - a, n) == pytest.approx(0.05)
        assert np.dot(big.polygon[(i + 1) % 5] - b, n) == pytest.approx(0.05)


@pytest.mark.parametrize("cells", [6, 8, 10, 14, 19])
def test_inflation_matches_nav2_formula(cells):
    cm = _single_obstacle()
    d = cells * 0.05
    expected = int(252 * math.exp(-3.0 * (d - 0.25)))
    assert cm.costs[40, 40 + cells] == expected
    assert cm.costs[40 + cells, 40] == expected


def test_lethal_inscribed_and_beyond_radius():
    cm = _single_obstacle(radius=0.5)
    assert cm.costs[40, 40] == LETHAL
    assert cm.costs[40, 45] == INSCRIBED          # 0.25 m = inscribed radius
    assert cm.costs[43, 43] == INSCRIBED          # 0.212 m diagonal
    assert cm.costs[40, 51] == 0                  # 0.55 m > inflation radius
    assert inflation_cost(np.array([0.0, 0.1, 0.6]), 0.25, 0.55, 3.0).tolist() == [LETHAL, INSCRIBED, 0]


def test_static_layer_trinary_and_unknown():
    g = np.array([[-1, 0, 50, 100]], np.int8)
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_layer=False, track_unknown_space=True,
                               lethal_cost_threshold=65, footprint=FP))
    cm.set_static_map(GridMap(g, 0.05))
    assert cm.costs[0].tolist() == [NO_INFORMATION, 0, 0, LETHAL]
    cm2 = Costmap(CostmapConfig(obstacle_layer=False, inflation_layer=False, track_unknown_space=False, footprint=FP))
    cm2.set_static_map(GridMap(g, 0.05))
    assert cm2.costs[0, 0] == 0


def test_obstacle_marking_and_raytrace_clearing():
    g = np.zeros((100, 100), np.int8)
    cm = Costmap(CostmapConfig(inflation_layer=False, footprint=FP))
    cm.set_static_map(GridMap(g, 0.05))
    ranges = np.full(360, np.inf)
    ranges[180] = 1.0                            # angle 0 → obstacle at (3.5, 2.5)
    scan = Scan(ranges, -math.pi, 2 * math.pi / 360, 0.05, 12.0)
    cm.update_scan(scan, (2.5, 2.5, 0.0))
    assert cm.cost_at(3.5 + 0.01, 2.5 + 0.01) == LETHAL
    ranges[180] = 2.0                            # the obstacle moved away: the old cell is cleared by the ray
    cm.update_scan(Scan(ranges, -math.pi, 2 * math.pi / 360, 0.05, 12.0), (2.5, 2.5, 0.0))
    assert cm.cost_at(3.51, 2.51) == 0
    assert cm.cost_at(4.51, 2.51) == LETHAL
    far = np.full(360, np.inf)
    far[270] = 2.8                               # +y beam beyond obstacle_max_range (2.5 m): clears, never marks
    cm.update_scan(Scan(far, -math.pi, 2 * math.pi / 360, 0.05, 12.0), (2.5, 1.0, 0.0))
    assert cm.cost_at(2.51, 3.81) == 0


def test_unknown_master_overridden_by_obstacle_clearing():
    g = np.full((100, 100), -1, np.int8)
    cm = Costmap(CostmapConfig(inflation_layer=False, footprint=FP))
    cm.set_static_map(GridMap(g, 0.05))
    ranges = np.full(360, 2.0)
    cm.update_scan(Scan(ranges, -math.pi, 2 * math.pi / 360, 0.05, 12.0), (2.5, 2.5, 0.0))
    assert cm.cost_at(3.0, 2.5) == 0             # seen free
    assert cm.cost_at(2.51, 4.51) == LETHAL      # marked
    assert cm.cost_at(0.2, 0.2) == NO_INFORMATION
    cm.clear()
    assert cm.cost_at(3.0, 2.5) == NO_INFORMATION


def test_incremental_growth_equals_full_recompute():
    rng = np.random.default_rng(3)
    full = np.where(rng.random((160, 200)) < 0.02, 100, 0).astype(np.int8)
    cfg = dict(obstacle_layer=False, inflation_radius=0.55, cost_scaling_factor=3.0, footprint=FP)
    inc = Costmap(CostmapConfig(**cfg))
    small = full[40:120, 50:150].copy()
    inc.set_static_map(GridMap(small, 0.05, origin_x=2.5, origin_y=2.0))
    grown = full.copy()
    grown[:, 180:] = -1
    inc.set_static_map(GridMap(grown, 0.05))                     # grows + re-frames (aligned)
    inc.set_static_map(GridMap(full, 0.05))                      # more becomes known
    ref = Costmap(CostmapConfig(**cfg))
    ref.set_static_map(GridMap(full, 0.05))
    assert np.array_equal(inc.costs, ref.costs)


def test_rolling_window_follows_robot_and_keeps_marks():
    cfg = CostmapConfig(rolling_window=True, width=3.0, height=3.0, static_layer=False, inflation_layer=False,
                        footprint=FP)
    cm = Costmap(cfg)
    cm.update_origin(0.0, 0.0)
    ranges = np.full(360, np.inf)
    ranges[180] = 1.0
    cm.update_scan(Scan(ranges, -math.pi, 2 * math.pi / 360, 0.05, 12.0), (0.0, 0.0, 0.0))
    assert cm.cost_at(1.01, 0.01) == LETHAL
    cm.update_origin(0.5, 0.3)
    assert cm.cost_at(1.01, 0.01) == LETHAL
    assert cm.origin_x == pytest.approx(-1.0)
    assert cm.origin_y == pytest.approx(-1.2)
