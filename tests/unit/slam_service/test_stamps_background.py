"""Bursty stamps are judged against the stream's own period; the loop solve runs off the scan path."""

from __future__ import annotations

import math

import numpy as np

from robonix_common.geometry import compose
from slam_service.core import SlamConfig, SlamEngine
from slam_service.core.background import merged_poses
from slam_service.core.motion import ScanClock, step_times


def test_scan_clock_mean_period_and_step_times() -> None:
    clock = ScanClock()
    assert clock.period() is None
    for t in (0.0, 0.01, 0.4, 0.41, 0.8):  # bursts: pairs 10 ms apart every 0.4 s
        clock.tick(t)
    assert math.isclose(clock.period(), 0.2)
    c = SlamConfig()
    assert step_times(c, 0.01, 0.2) == (0.2, 0.0)  # a burst: rate judged over a mean period, no gap
    assert step_times(c, 0.39, 0.2) == (0.39, 0.0)  # the pause between bursts is not a data gap
    assert step_times(c, 3.0, 0.2) == (3.0, 3.0)  # a real gap still counts
    assert step_times(c, 0.005, None) == (0.1, 0.005)  # before the clock knows: 10 Hz assumed


def test_bursty_stamps_are_not_odometry_jumps(apartment_recording) -> None:
    _, rec = apartment_recording
    eng = SlamEngine(SlamConfig(loop_closure=False))
    # same scans and odometry, stamped in bursts: two scans 5 ms apart, then a 0.195 s pause
    stamps = [0.2 * (k // 2) + 0.005 * (k % 2) for k in range(150)]
    for k in range(150):
        eng.process(rec.scans[k], rec.odom[k], stamps[k])
    assert eng.stats.odom_jumps == 0
    assert eng.stats.wide_searches == 0
    assert eng.stats.scans_integrated > 10


def test_merged_poses_carry_later_nodes_rigidly() -> None:
    live = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0.1]])
    solved = np.array([[0.0, 0, 0], [1.0, 0.5, 0.2]])
    out = merged_poses(live, solved)
    np.testing.assert_allclose(out[:2], solved)
    delta = compose(solved[1], [-1.0, 0, 0])  # solved[1] o live[1]^-1
    for k in (2, 3):
        np.testing.assert_allclose(out[k], compose(delta, live[k]), atol=1e-12)


def test_background_solve_is_applied_at_a_fixed_node_and_deterministic(apartment_recording) -> None:
    _, rec = apartment_recording
    runs = []
    for _ in range(2):
        eng = SlamEngine(SlamConfig(optimize_in_background=True))  # opt-in: off by default (see SlamConfig)
        closed_at = []
        for scan, odom in zip(rec.scans, rec.odom, strict=True):
            u = eng.process(scan, odom)
            if u.loop_closed:
                closed_at.append(eng.graph.n_nodes)
        eng.flush()
        runs.append((eng.trajectory(), closed_at, eng.stats.loop_closures))
    assert runs[0][2] >= 1  # the apartment loop closes ...
    np.testing.assert_array_equal(runs[0][0], runs[1][0])  # ... the same way every run, whatever the timing
    assert runs[0][1] == runs[1][1]
