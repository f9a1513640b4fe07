"""Global planner: optimal-ish paths, obstacles, allow_unknown, tolerance, clear failures, safe smoothing."""

import math

import numpy as np
import pytest

from nav2_wrapper.core import INSCRIBED, Costmap, CostmapConfig, GlobalPlanner, PlannerConfig
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

FP = load_footprint()


def costmap(data, res=0.05, track_unknown=True):
    cm = Costmap(CostmapConfig(obstacle_layer=False, inflation_radius=0.55, cost_scaling_factor=3.0,
                               track_unknown_space=track_unknown, footprint=FP))
    cm.set_static_map(GridMap(np.asarray(data, np.int8), res))
    return cm


def walls(rows=120, cols=200):
    g = np.zeros((rows, cols), np.int8)
    g[0, :] = g[-1, :] = g[:, 0] = g[:, -1] = 100
    return g


def _assert_safe(cm, path):
    c = cm.cost_at(path[:, 0], path[:, 1])
    assert np.all(c < INSCRIBED), "path touches an inscribed/lethal cell"


def test_open_space_is_straight_and_short():
    cm = costmap(walls())
    r = GlobalPlanner().plan(cm, (1.0, 3.0), (9.0, 3.0))
    assert r.ok, r.reason
    assert r.length == pytest.approx(8.0, rel=0.01)
    assert np.allclose(r.path[0], (1.0, 3.0))
    assert np.allclose(r.path[-1], (9.0, 3.0))
    assert np.max(np.hypot(*np.diff(r.path, axis=0).T)) <= 0.05 + 1e-9


def test_goes_around_a_wall_close_to_optimal():
    g = walls()
    g[0:90, 95:100] = 100
    cm = costmap(g)
    fast = GlobalPlanner(PlannerConfig(heuristic_weight=1.1)).plan(cm, (2.0, 2.0), (8.0, 2.0))
    exact = GlobalPlanner(PlannerConfig(heuristic_weight=1.0, smooth_path=False)).plan(cm, (2.0, 2.0), (8.0, 2.0))
    assert fast.ok
    assert exact.ok
    assert fast.cost <= exact.cost * 1.1 + 1e-6
    assert fast.length <= exact.length * 1.02
    assert np.max(fast.path[:, 1]) > 4.5            # went over the wall's end (y = 4.5)
    _assert_safe(cm, fast.path)


def test_smoothing_never_cuts_corners():
    rng = np.random.default_rng(7)
    g = walls(160, 160)
    for _ in range(40):
        r, c = rng.integers(5, 150, 2)
        g[r:r + 6, c:c + 6] = 100
    cm = costmap(g)
    free = np.argwhere(cm.costs < INSCRIBED)
    pl = GlobalPlanner()
    for _ in range(15):
        a, b = free[rng.integers(len(free))], free[rng.integers(len(free))]
        s = cm.cell_to_world(a[1], a[0])
        e = cm.cell_to_world(b[1], b[0])
        r = pl.plan(cm, (float(s[0]), float(s[1])), (float(e[0]), float(e[1])))
        if r.ok:
            # check densely between every pair of consecutive points, not just at the points
            t = np.linspace(0, 1, 5)[:, None, None]
            seg = r.path[:-1][None] + t * (r.path[1:] - r.path[:-1])[None]
            _assert_safe(cm, seg.reshape(-1, 2))


def test_allow_unknown_on_and_off():
    g = walls()
    g[1:-1, 95:105] = -1                              # an unknown band splits the room
    cm = costmap(g)
    assert GlobalPlanner(PlannerConfig(allow_unknown=True)).plan(cm, (2.0, 3.0), (8.0, 3.0)).ok
    r = GlobalPlanner(PlannerConfig(allow_unknown=False)).plan(cm, (2.0, 3.0), (8.0, 3.0))
    assert not r.ok
    assert "no path" in r.reason


def test_tolerance_picks_nearest_free_cell():
    g = walls()
    g[50:70, 140:160] = 100                           # box; goal at its edge is inscribed/lethal
    cm = costmap(g)
    goal = (6.9, 3.0)                                 # 0.1 m from the box face: inscribed
    assert cm.cost_at(*goal) >= INSCRIBED
    ok = GlobalPlanner(PlannerConfig(tolerance=0.3)).plan(cm, (2.0, 3.0), goal)
    assert ok.ok
    assert math.hypot(*(ok.path[-1] - goal)) <= 0.3
    bad = GlobalPlanner(PlannerConfig(tolerance=0.05)).plan(cm, (2.0, 3.0), goal)
    assert not bad.ok
    assert "tolerance" in bad.reason


def test_no_path_is_a_clear_failure():
    g = walls()
    g[40:80, 120] = g[40:80, 160] = 100
    g[40, 120:161] = g[80, 120:161] = 100             # closed room
    cm = costmap(g)
    r = GlobalPlanner().plan(cm, (2.0, 3.0), (7.0, 3.0))
    assert not r.ok
    assert r.reason.startswith("no path")
    assert "not reachable" in r.reason
    off = GlobalPlanner().plan(cm, (2.0, 3.0), (70.0, 3.0))
    assert not off.ok
    assert "off the costmap" in off.reason


def test_start_inside_inscribed_band_escapes():
    g = walls()
    cm = costmap(g)
    r = GlobalPlanner().plan(cm, (0.2, 3.0), (5.0, 3.0))   # 0.15 m from the wall
    assert r.ok
    _assert_safe(cm, r.path[r.path[:, 0] > 0.6])
