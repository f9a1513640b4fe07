"""Full engine on the two-lap apartment drive with drifting odometry (the issue's acceptance)."""

from __future__ import annotations

from robonix_common.grid import GridMap
from slam_service.core import ate_rmse, occupied_iou
from slam_service.core.engine import TIMING_SAMPLES

from .conftest import MappingRun


def test_loop_closure_meets_ate_and_beats_no_loop_closure(mapping_with_lc: MappingRun,
                                                          mapping_without_lc: MappingRun) -> None:
    est, gt = mapping_with_lc.ate_inputs
    odom_ate = ate_rmse(mapping_with_lc.rec.odom[mapping_with_lc.node_index], gt)
    ate_lc = ate_rmse(est, gt)
    ate_no = ate_rmse(*mapping_without_lc.ate_inputs)
    print(f"ATE (start frame): odometry {odom_ate:.3f} m, LC off {ate_no:.4f} m, LC on {ate_lc:.4f} m")
    assert odom_ate > 0.3  # the drive really drifts
    assert mapping_with_lc.engine.stats.loop_closures >= 1
    assert mapping_without_lc.engine.stats.loop_closures == 0
    assert ate_lc <= 0.05
    assert ate_no >= 1.3 * ate_lc  # measurably worse without loop closure


def test_map_iou_vs_ground_truth(mapping_with_lc: MappingRun, mapping_without_lc: MappingRun) -> None:
    gt = mapping_with_lc.world.ground_truth_grid()
    iou = occupied_iou(mapping_with_lc.engine.map(), gt, observed_only=True)
    iou_no = occupied_iou(mapping_without_lc.engine.map(), gt, observed_only=True)
    print(f"occupied IoU (1-cell tolerance, observed walls): LC on {iou:.3f}, LC off {iou_no:.3f}")
    assert iou >= 0.85
    assert iou > iou_no


def test_engine_counters_and_map_export(mapping_with_lc: MappingRun) -> None:
    eng = mapping_with_lc.engine
    s = eng.stats
    assert s.scans_received == len(mapping_with_lc.rec.scans)
    assert s.scans_integrated + s.scans_gated + s.scans_skipped_invalid == s.scans_received
    assert s.scans_gated > s.scans_integrated  # motion gating skips most scans at 10 Hz
    assert s.beams_nan > 0  # the recording has dropouts; they are counted, not used
    m = eng.map()
    assert isinstance(m, GridMap)
    assert set(map(int, set(m.data.ravel().tolist()))) <= {-1, 0, 100}
    # the map covers the apartment (grown in chunks from nothing)
    assert m.origin_x <= 0.0
    assert m.origin_y <= 0.0
    assert m.origin_x + m.width * m.resolution >= 10.0
    assert m.origin_y + m.height * m.resolution >= 8.0
    assert eng.optimize_times
    # timing samples are bounded (an all-day run must not grow them); the batch counter keeps counting
    assert eng.optimize_times.maxlen == eng.rerender_times.maxlen == TIMING_SAMPLES
    assert eng.rerender_batches >= len(eng.rerender_times) > 0
    assert eng.last_optimize is not None
