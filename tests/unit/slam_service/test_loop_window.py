"""The loop match's search window follows the pose uncertainty accrued since the last loop closure: a
robot that drifted further than the fixed window while its lidar could not pin the pose still closes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_eval.synthetic import Recording, World, apartment_world, drive
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse
from slam_service.core.motion import loop_windows

BLIND_FROM, BLIND_SCANS, SLIP_M = 900, 20, 1.5


def test_loop_windows_grow_with_drift_and_are_bounded() -> None:
    c = SlamConfig()
    w = loop_windows(c, 0.0, 0.0)
    assert (w.xy, w.theta, w.wide) == (c.loop_search_window_xy, c.loop_search_window_theta, False)
    w = loop_windows(c, 0.2, 0.05)
    assert w.xy == pytest.approx(c.loop_search_window_xy + 0.6)
    assert w.theta == pytest.approx(c.loop_search_window_theta + 0.15)
    assert w.wide
    w = loop_windows(c, 1e9, math.inf)
    assert (w.xy, w.theta) == (c.loop_search_window_xy_max, c.loop_search_window_theta)  # inf: not widened
    assert loop_windows(c, -1.0, -1.0).xy == c.loop_search_window_xy
    # a cap below the base window never shrinks it
    c2 = SlamConfig(loop_search_window_xy_max=0.5)
    assert loop_windows(c2, 5.0, 0.0).xy == c2.loop_search_window_xy


@pytest.fixture(scope="module")
def two_laps() -> Recording:
    base = apartment_world()
    ring = base.waypoints[:-3]
    return drive(World(base.name, base.rects, ring * 2 + base.waypoints[-3:]), seed=5)


def _blind_slip_run(rec: Recording, config: SlamConfig) -> tuple[SlamEngine, float, float]:
    """Second lap: the lidar sees only clutter for 2 s while the odometry slips 1.5 m sideways (and keeps
    that offset). Returns the engine, the ATE and the widest loop window it used."""
    rng = np.random.default_rng(0)
    eng = SlamEngine(config)
    widest = 0.0
    for k, (s, o) in enumerate(zip(rec.scans, rec.odom, strict=True)):
        odom = np.asarray(o, dtype=float)
        if k >= BLIND_FROM:
            odom = odom + np.array([0.0, SLIP_M * min(1.0, (k - BLIND_FROM) / BLIND_SCANS), 0.0])
        if BLIND_FROM <= k < BLIND_FROM + BLIND_SCANS:
            s = Scan(rng.uniform(0.3, 0.6, s.ranges.size).astype(np.float32), s.angle_min, s.angle_increment,
                     s.range_min, s.range_max, s.stamp)
        eng.process(s, odom)
        widest = max(widest, eng.loop_windows().xy)
    eng.flush()
    # scored by node stamp: lifelong pruning removes second-lap nodes whose place the first lap covers
    idx = [int(i) for i in np.searchsorted(rec.stamps, eng.node_stamps() - 1e-9)]
    return eng, ate_rmse(eng.trajectory(), rec.gt[idx]), widest


def test_loop_window_reaches_a_pose_off_by_more_than_the_fixed_window(two_laps: Recording) -> None:
    c = SlamConfig()
    assert c.loop_search_window_xy < SLIP_M  # the fixed window alone cannot reach the true pose
    eng, ate, widest = _blind_slip_run(two_laps, c)
    assert widest > c.loop_search_window_xy + 0.3  # the blind stretch widened the window well past the fixed one
    assert ate < 0.05
    assert eng.loop_windows().xy == c.loop_search_window_xy  # a closure resets it
    fixed = SlamConfig(loop_search_window_xy_max=c.loop_search_window_xy,
                       loop_search_window_theta_max=c.loop_search_window_theta)
    _, ate_fixed, widest_fixed = _blind_slip_run(two_laps, fixed)
    assert widest_fixed == c.loop_search_window_xy
    assert ate_fixed > 0.2  # with the fixed window the slip stays in the map
