"""After a loop closure the map is re-drawn a few nodes per ``process`` call, never all at once on the scan
path; the trajectory does not depend on that budget and ``flush()`` brings the map fully up to date."""

from __future__ import annotations

import numpy as np

from robonix_common.geometry import transform_points
from robonix_eval.synthetic import Recording, World
from slam_service.core import SlamConfig, SlamEngine
from slam_service.core.engine import _render_shift
from slam_service.core.occupancy import LogOddsGrid

from .conftest import MappingRun

BUDGET = 5


def _drawn_from_scratch(eng: SlamEngine, poses: np.ndarray) -> LogOddsGrid:
    c = eng.config
    g = LogOddsGrid(c.resolution, hit=c.log_odds_hit, miss=c.log_odds_miss, chunk=c.grid_chunk)
    for k, pose in enumerate(poses):
        g.integrate(transform_points(pose, eng._origins[k][None])[0], transform_points(pose, eng._points[k]))
    return g


def _logodds_at(g: LogOddsGrid, c0: int, r0: int, shape: tuple[int, int]) -> np.ndarray:
    """``g``'s log-odds over global cells [r0, r0 + h) x [c0, c0 + w) (zero where it has none)."""
    out = np.zeros(shape, dtype=np.float64)
    h, w = g.logodds.shape
    rs, cs = max(r0, g.r0), max(c0, g.c0)
    re, ce = min(r0 + shape[0], g.r0 + h), min(c0 + shape[1], g.c0 + w)
    out[rs - r0:re - r0, cs - c0:ce - c0] = g.logodds[rs - g.r0:re - g.r0, cs - g.c0:ce - g.c0]
    return out


def test_rerender_is_spread_over_calls_and_flush_completes_it(
        apartment_recording: tuple[World, Recording], mapping_with_lc: MappingRun) -> None:
    _, rec = apartment_recording
    eng = SlamEngine(SlamConfig(rerender_nodes_per_scan=BUDGET))
    per_call, backlog = [], []
    for scan, odom in zip(rec.scans, rec.odom, strict=True):
        before = eng.stats.map_nodes_rerendered
        eng.process(scan, odom)
        per_call.append(eng.stats.map_nodes_rerendered - before)
        backlog.append(eng.stats.map_nodes_pending)
    assert eng.stats.loop_closures >= 1
    assert max(backlog) > BUDGET  # a closure moved more nodes than one call may draw ...
    assert max(per_call) == BUDGET  # ... yet no call drew more than the budget
    assert sum(per_call) > max(backlog)  # and the backlog was worked off over later calls

    eng.flush()  # (also applies a background loop solve still pending at the last scan, as the fixture's did)
    # the map lags, the trajectory never does: identical to the run with the default budget
    np.testing.assert_array_equal(eng.trajectory(), mapping_with_lc.engine.trajectory())
    assert eng.stats.map_nodes_pending == 0
    drawn = np.asarray(eng._rendered)
    # every node is drawn within re_render_threshold (at max range) of its optimised pose ...
    assert _render_shift(drawn, eng.trajectory(), eng.config.max_range).max() <= eng.config.re_render_threshold
    assert not np.array_equal(drawn, eng.trajectory())  # (nodes below the threshold keep their first drawing)
    fresh = _drawn_from_scratch(eng, drawn)
    live = eng.grid
    shape = (max(live.r0 + live.logodds.shape[0], fresh.r0 + fresh.logodds.shape[0]) - min(live.r0, fresh.r0),
             max(live.c0 + live.logodds.shape[1], fresh.c0 + fresh.logodds.shape[1]) - min(live.c0, fresh.c0))
    c0, r0 = min(live.c0, fresh.c0), min(live.r0, fresh.r0)
    # ... and the grid stores exact sums: after all the subtract-and-redraw steps it equals drawing every
    # node once at the pose it is drawn at
    np.testing.assert_allclose(_logodds_at(live, c0, r0, shape), _logodds_at(fresh, c0, r0, shape), atol=1e-3)
