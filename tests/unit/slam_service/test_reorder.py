"""Stamps: slightly late scans are sorted into order (not skipped), duplicates are skipped and counted."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import Scan, SlamConfig, SlamEngine
from slam_service.core.reorder import ReorderBuffer


@pytest.fixture(scope="module")
def rec():
    return drive(apartment_world(), seed=2)


def _released(buf: ReorderBuffer, stamps: list[float]) -> list[float]:
    out = []
    for s in stamps:
        _, due = buf.push(s, s)
        out += [t for t, _ in due]
    return out + [t for t, _ in buf.flush()]


def test_buffer_sorts_within_the_window_and_drops_later_ones() -> None:
    buf: ReorderBuffer[float] = ReorderBuffer(0.3, adaptive=False)
    stamps = [0.0, 0.2, 0.1, 0.3, 0.5, 0.4, 0.9, 0.45, 1.0]  # 0.45 arrives after 0.9 was seen: too late
    out = _released(buf, stamps)
    assert out == sorted(out)
    assert 0.45 not in out
    assert out == [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.9, 1.0]


def test_output_is_delayed_by_at_most_the_window() -> None:
    buf: ReorderBuffer[float] = ReorderBuffer(0.3, adaptive=False)
    assert buf.push(0.0, 0.0)[1] == []  # held
    assert buf.push(0.2, 0.2)[1] == []
    assert [t for t, _ in buf.push(0.3, 0.3)[1]] == [0.0]  # newest - window reached 0.0
    assert [t for t, _ in buf.flush()] == [0.2, 0.3]


def test_adaptive_buffer_has_zero_latency_until_the_first_late_scan() -> None:
    buf: ReorderBuffer[float] = ReorderBuffer(0.3, adaptive=True)
    assert [t for t, _ in buf.push(0.0, 0.0)[1]] == [0.0]
    assert [t for t, _ in buf.push(0.1, 0.1)[1]] == [0.1]
    verdict, due = buf.push(0.05, 0.05)  # the first late scan switches sorting on
    assert verdict == "late"
    assert due == []
    assert buf.holding
    assert buf.push(0.3, 0.3)[1] == []
    assert buf.push(0.2, 0.2)[0] == "ok"
    assert [t for t, _ in buf.push(0.6, 0.6)[1]] == [0.2, 0.3]


def test_exact_duplicates_are_reported() -> None:
    buf: ReorderBuffer[str] = ReorderBuffer(0.3, adaptive=True)
    assert buf.push(1.0, "a", key=11)[0] == "ok"
    assert buf.push(1.0, "a", key=11)[0] == "duplicate"
    assert buf.push(1.0, "b", key=12)[0] == "ok"  # same stamp, other data: not a duplicate


def test_engine_sorts_shuffled_scans_like_the_ordered_stream(rec) -> None:
    n = 300
    ordered = SlamEngine(SlamConfig(loop_closure=False))
    for s, o in zip(rec.scans[:n], rec.odom[:n], strict=True):
        ordered.process(s, o)
    rng = np.random.default_rng(0)
    order = np.argsort(rec.stamps[:n] + rng.uniform(0, 0.25, n), kind="stable")
    assert (order != np.arange(n)).sum() > 50
    eng = SlamEngine(SlamConfig(loop_closure=False, reorder_adaptive=False))
    for i in order:
        eng.process(rec.scans[i], rec.odom[i])
    held = eng.stats.scans_integrated + eng.stats.scans_gated
    eng.flush()
    assert eng.stats.scans_integrated + eng.stats.scans_gated > held  # flush released the held tail
    assert eng.stats.scans_skipped_time == 0
    assert eng.stats.scans_reordered > 50
    assert np.all(np.diff(eng.node_stamps()) > 0)
    assert eng.graph.n_nodes == ordered.graph.n_nodes
    assert np.abs(eng.trajectory() - ordered.trajectory()).max() < 1e-9  # same input order, same result


def test_adaptive_engine_loses_at_most_one_scan_of_a_shuffled_stream(rec) -> None:
    n = 200
    rng = np.random.default_rng(1)
    order = np.argsort(rec.stamps[:n] + rng.uniform(0, 0.3, n), kind="stable")
    eng = SlamEngine()
    for i in order:
        eng.process(rec.scans[i], rec.odom[i])
    eng.flush()
    st = eng.stats
    assert st.scans_skipped_time <= 1  # the late scan that switched sorting on
    assert st.scans_integrated + st.scans_gated == n - st.scans_skipped_time
    assert np.all(np.diff(eng.node_stamps()) > 0)


def test_duplicates_are_skipped_counted_and_warned_once(rec, caplog: pytest.LogCaptureFixture) -> None:
    eng = SlamEngine()
    with caplog.at_level(logging.WARNING, logger="slam_service.core.engine"):
        for s, o in zip(rec.scans[:30], rec.odom[:30], strict=True):
            eng.process(s, o)
            u = eng.process(Scan(s.ranges.copy(), s.angle_min, s.angle_increment, s.range_min, s.range_max, s.stamp,
                                 s.mount), o)
            assert u.skipped_reason == "duplicate scan"
    assert eng.stats.scans_duplicate == 30
    assert sum("duplicate" in r.getMessage() for r in caplog.records) == 1


def test_reorder_window_is_a_declared_param() -> None:
    assert SlamConfig().reorder_window_s == pytest.approx(1.0)  # real logs: lines up to 0.9 s out of order
    with pytest.raises(ValueError, match="SlamConfig.reorder_window_s"):
        SlamConfig(reorder_window_s=-1.0)
