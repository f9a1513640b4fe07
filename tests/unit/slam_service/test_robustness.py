"""Bad input never crashes the engine: skipped with a counted warning, or a clear error."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_common.geometry import compose
from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import Scan, SlamConfig, SlamEngine


@pytest.fixture(scope="module")
def rec():
    return drive(apartment_world(), seed=4)


def _scan(ranges: np.ndarray, stamp: float = 0.0) -> Scan:
    return Scan(ranges.astype(np.float32), -math.pi, 2 * math.pi / 360, 0.05, 12.0, stamp)


def test_nan_inf_beams_are_dropped_and_counted(rec) -> None:
    eng = SlamEngine()
    s = rec.scans[0]
    r = s.ranges.copy()
    r[::7] = np.nan
    r[1::11] = np.inf
    r[2::13] = 50.0
    r[3::17] = 0.01
    u = eng.process(Scan(r, s.angle_min, s.angle_increment, s.range_min, s.range_max, 0.0), rec.odom[0])
    assert u.integrated
    assert eng.stats.beams_nan == np.count_nonzero(np.isnan(r))
    assert eng.stats.beams_inf == np.count_nonzero(np.isinf(r))
    assert eng.stats.beams_out_of_range == np.count_nonzero(r == np.float32(0.01))
    # beyond range_max is the no-return sentinel, like +inf: not an obstacle, counted separately
    assert eng.stats.beams_no_return == np.count_nonzero((r == 50.0) | np.isposinf(r))


@pytest.mark.parametrize("ranges", [np.zeros(0), np.full(360, np.nan), np.full(360, np.inf), np.full(360, 0.0),
                                    np.full(5, 2.0)])
def test_empty_or_invalid_scans_are_skipped(ranges: np.ndarray) -> None:
    eng = SlamEngine()
    u = eng.process(_scan(ranges), [0, 0, 0])
    assert not u.integrated
    assert u.skipped_reason
    assert eng.stats.scans_skipped_invalid == 1
    assert eng.graph.n_nodes == 0


@pytest.mark.parametrize("kwargs", [dict(angle_increment=float("nan")), dict(range_min=5.0, range_max=1.0),
                                    dict(mount=(0, 0)), dict(angle_min=None)])
def test_malformed_scan_metadata_is_skipped(kwargs: dict) -> None:
    base = dict(ranges=np.full(360, 2.0, np.float32), angle_min=-math.pi, angle_increment=0.0175)
    eng = SlamEngine()
    u = eng.process(Scan(**{**base, **kwargs}), [0, 0, 0])
    assert not u.integrated
    assert eng.stats.scans_skipped_invalid == 1
    assert any(k in u.skipped_reason for k in kwargs)


@pytest.mark.parametrize("odom", [[0, 0], [0, np.nan, 0], "pose", None])
def test_bad_odometry_is_skipped(rec, odom) -> None:
    eng = SlamEngine()
    u = eng.process(rec.scans[0], odom)
    assert not u.integrated
    assert "odom_pose" in u.skipped_reason


def test_not_a_scan_and_time_going_backwards(rec) -> None:
    eng = SlamEngine()
    assert eng.process("scan", rec.odom[0]).skipped_reason.startswith("expected a Scan")  # type: ignore[arg-type]
    assert eng.process(rec.scans[10], rec.odom[10]).integrated
    u = eng.process(rec.scans[5], rec.odom[5])
    assert not u.integrated
    assert eng.stats.scans_skipped_time == 1


def test_odom_reset_is_matched_not_followed_and_pose_stays_continuous(rec) -> None:
    """An odometry frame jump between two scans is faster than the robot can move: the scan is matched at
    'the robot did not move' too, that seed wins, and map->odom absorbs the jump (nothing dropped)."""
    eng = SlamEngine()
    jump = np.array([5.0, -3.0, 1.5])  # the odom frame moves, e.g. an odometry reset
    errs = []
    for k, (s, o) in enumerate(zip(rec.scans[:200], rec.odom[:200], strict=True)):
        odom = compose(jump, o) if k >= 100 else o
        u = eng.process(s, odom)
        if k == 100:
            assert not u.skipped_reason
        errs.append(np.hypot(*(u.pose_map[:2] - rec.gt[k][:2])))
    assert eng.stats.odom_jumps == 1
    assert eng.stats.odom_glitches == 1
    assert max(errs[100:]) < 0.1  # tracking continues in the map frame


def test_legacy_drop_flag_restores_the_old_jump_guard(rec) -> None:
    eng = SlamEngine(SlamConfig(drop_odom_jumps=True))
    jump = np.array([5.0, -3.0, 1.5])
    for k, (s, o) in enumerate(zip(rec.scans[:120], rec.odom[:120], strict=True)):
        u = eng.process(s, compose(jump, o) if k >= 100 else o)
        if k == 100:
            assert u.skipped_reason.startswith("odometry jump")
    assert eng.stats.odom_jumps == 1


def test_config_validation_names_the_field() -> None:
    with pytest.raises(ValueError, match="SlamConfig.resolution"):
        SlamConfig(resolution=0)
    with pytest.raises(ValueError, match="SlamConfig.coarse_factor"):
        SlamConfig(coarse_factor=2.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="SlamConfig.loop_min_response"):
        SlamConfig(loop_min_response=1.5)
    with pytest.raises(ValueError, match="unknown field"):
        SlamConfig.from_dict({"resolutoin": 0.05})
    with pytest.raises(ValueError, match="mode"):
        SlamEngine(mode="slam")  # type: ignore[arg-type]


def test_localization_without_map_is_a_clear_error() -> None:
    eng = SlamEngine()
    with pytest.raises(ValueError, match="needs a map"):
        eng.set_mode("localization")
    eng2 = SlamEngine(mode="localization")
    u = eng2.process(_scan(np.full(360, 2.0)), [0, 0, 0])
    assert not u.integrated
    assert "without a map" in u.skipped_reason


def test_reset_clears_everything(rec) -> None:
    eng = SlamEngine()
    for s, o in zip(rec.scans[:50], rec.odom[:50], strict=True):
        eng.process(s, o)
    assert eng.graph.n_nodes > 0
    eng.reset()
    assert eng.graph.n_nodes == 0
    assert eng.stats.scans_received == 0
    assert (eng.map().data == -1).all()
