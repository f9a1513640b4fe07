"""Never discard motion: large or uncertain odometry steps widen the search; unmatched ones still enter
the graph (large covariance); the loop-candidate radius follows the accrued uncertainty."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse
from slam_service.core.motion import loop_radius, search_windows, suspect_step, unmatched_sigmas
from slam_service.core.posegraph import EDGE_ODOM


@pytest.fixture(scope="module")
def rec():
    return drive(apartment_world(), seed=3, max_yaw_rate=1.0)


def test_normal_steps_keep_the_configured_windows() -> None:
    c = SlamConfig()
    w = search_windows(c, 0.25, 0.2, 0.1)
    assert (w.xy, w.theta, w.wide) == (c.search_window_xy, c.search_window_theta, False)


@pytest.mark.parametrize(("dist", "rot", "gap"), [(0.0, 1.06, 3.0), (0.8, 0.0, 0.1), (0.0, 0.0, 2.0)])
def test_wide_steps_grow_the_windows_with_the_step_and_the_gap(dist: float, rot: float, gap: float) -> None:
    c = SlamConfig()
    w = search_windows(c, dist, rot, gap)
    assert w.wide
    assert w.theta == pytest.approx(min(c.max_search_window_theta, c.search_window_theta + c.window_growth * rot
                                        + c.window_growth_gap * gap))
    assert w.xy == pytest.approx(min(c.max_search_window_xy, c.search_window_xy + c.window_growth * dist
                                     + c.window_growth_gap * gap))
    huge = search_windows(c, 50.0, 3.0, 100.0)
    assert (huge.xy, huge.theta) == (c.max_search_window_xy, c.max_search_window_theta)  # bounded


def test_suspect_steps_are_faster_than_the_robot() -> None:
    c = SlamConfig()
    assert not suspect_step(c, 0.0, 1.06, 3.0)  # the real-log case: 1.06 rad over a 3 s gap is plausible
    assert suspect_step(c, 0.0, 0.6, 0.1)  # 6 rad/s
    assert suspect_step(c, 5.0, 0.0, 0.1)
    assert not suspect_step(c, 0.04, 0.1, 0.1)


def test_loop_radius_grows_with_drift_and_is_bounded() -> None:
    c = SlamConfig()
    assert loop_radius(c, 0.0) == c.loop_search_radius
    assert loop_radius(c, 1.0) == pytest.approx(c.loop_search_radius + 3.0)
    assert loop_radius(c, 1e9) == c.loop_search_radius_max


def _gap_over_turns(rec) -> tuple[list[int], float]:
    """Recording indices with the scans of the first two corner turns (and the leg between) removed, and
    the true rotation across the gap. The synthetic corners are < 1 rad each; two make the step > 1 rad."""
    fast = np.abs(np.diff(np.unwrap(rec.gt[:, 2]))) / 0.1 >= 0.9
    starts = [k for k in range(1, len(fast) - 5) if fast[k:k + 5].all() and not fast[k - 1]]
    k0 = starts[0] - 2
    k1 = starts[1] + int(np.argmin(fast[starts[1]:])) + 2
    turned = abs(math.remainder(rec.gt[k1, 2] - rec.gt[k0 - 1, 2], 2 * math.pi))
    return [k for k in range(len(rec.scans)) if not k0 <= k < k1], turned


@pytest.mark.parametrize("drop", [False, True])
def test_gap_during_a_turn_is_matched_with_wider_windows(rec, drop: bool) -> None:
    keep, turned = _gap_over_turns(rec)
    assert turned > 1.0  # more than the old jump guard allowed
    keep = [k for k in keep if k < 400]
    eng = SlamEngine(SlamConfig(loop_closure=False, drop_odom_jumps=drop))
    idx = [k for k in keep if eng.process(rec.scans[k], rec.odom[k]).integrated]
    ate = ate_rmse(eng.trajectory(), rec.gt[idx])
    if drop:  # the old guard threw the rotation away: the rest of the map is rotated
        assert eng.stats.odom_jumps == 1
        assert ate > 0.3
    else:
        assert eng.stats.odom_jumps == 0
        assert eng.stats.wide_searches >= 1
        assert eng.stats.match_failures == 0
        assert ate < 0.05


def test_an_unmatchable_wide_step_still_enters_the_graph_with_a_large_covariance(rec) -> None:
    eng = SlamEngine(SlamConfig(loop_closure=False))
    for s, o in zip(rec.scans[:60], rec.odom[:60], strict=True):
        eng.process(s, o)
    n = eng.graph.n_nodes
    s = rec.scans[60]
    junk = Scan(np.random.default_rng(0).uniform(0.3, 0.6, s.ranges.size), s.angle_min, s.angle_increment,
                s.range_min, s.range_max, s.stamp + 4.0)  # after a 4 s gap, a scan that matches nothing
    odom = rec.odom[59] + np.array([0.0, 0.0, 1.2])
    u = eng.process(junk, odom)
    assert u.integrated
    assert not u.skipped_reason
    assert eng.graph.n_nodes == n + 1
    assert eng.stats.unmatched_steps == 1
    assert eng.graph.edge_kind[-1] == EDGE_ODOM
    sxy, sth = unmatched_sigmas(eng.config, *eng._step_motion)
    info = np.asarray(eng.graph.edge_info[-1])
    assert info[2, 2] == pytest.approx(1 / sth**2)
    assert sth > 5 * eng.config.odom_sigma_theta  # much weaker than a normal odometry edge
    assert eng._drift > 0  # the loop-candidate radius widens after it
    # the odometry's rotation was kept, not thrown away
    assert math.remainder(u.pose_map[2] - eng.trajectory()[-2, 2], 2 * math.pi) == pytest.approx(1.2, abs=0.25)
