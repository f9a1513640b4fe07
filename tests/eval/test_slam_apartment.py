"""SLAM on MuJoCo scans: the apartment loop with drifting odometry, scored against ground truth.

Two settings, each one drive feeding two engines (loop closure on and off) with identical input:
- realistic: the sim's realistic odometry drift and 1 cm lidar noise. Scan matching alone is already
  ~5 mm here, so loop closure cannot gain much; it must not hurt (verified, floored, Huber-weighted loops).
- hard: ~2.5x the odometry drift and a cheap lidar's view for SLAM (120 beams, 2.5 cm noise): scan
  matching alone drifts, and loop closure must bring ATE within 5 cm and measurably below LC off.

IoU definition (slam_service.core.occupied_iou): occupied cells (>= 65) of the SLAM map vs the scene
rasterised at the SLAM resolution with only obstacles that reach the lidar plane (height >= lidar mount z),
a cell counts as matched if the other set has an occupied cell within 1 cell (Chebyshev), and ground-truth
walls the map never observed (no known cell within 1 cell) are left out.
"""

from __future__ import annotations

import pytest

from robonix_eval.slam_loop import SlamLoopResult, run_slam_loops


@pytest.fixture(scope="module")
def realistic() -> tuple[SlamLoopResult, SlamLoopResult]:
    return run_slam_loops("apartment", seed=0)


@pytest.fixture(scope="module")
def hard() -> tuple[SlamLoopResult, SlamLoopResult]:
    return run_slam_loops("apartment", seed=0, hard=True)


def _show(name: str, on: SlamLoopResult, off: SlamLoopResult) -> None:
    print(f"\n{name}: ATE LC on {on.ate_rmse * 100:.2f} cm ({on.loop_closures} closures), LC off "
          f"{off.ate_rmse * 100:.2f} cm, odometry {on.odom_ate_rmse * 100:.1f} cm; IoU on {on.iou:.3f} off {off.iou:.3f}")


def test_route_driven_and_odometry_drifts(realistic: tuple[SlamLoopResult, SlamLoopResult]) -> None:
    on, off = realistic
    assert all(g.succeeded for g in on.goals), [g.detail for g in on.goals]
    assert on.odom_ate_rmse > 0.15  # the drift SLAM has to remove is real
    assert on.loop_closures >= 3
    assert off.loop_closures == 0


def test_realistic_loop_closure_is_never_harmful(realistic: tuple[SlamLoopResult, SlamLoopResult]) -> None:
    on, off = realistic
    _show("realistic", on, off)
    assert on.ate_rmse <= 0.05 and on.iou >= 0.85, (on.ate_rmse, on.iou)
    assert off.ate_rmse <= 0.05 and off.iou >= 0.85, (off.ate_rmse, off.iou)
    assert on.ate_rmse <= off.ate_rmse + 0.01  # verified closures: no worse than scan matching alone


def test_hard_acceptance_loop_closure_needed(hard: tuple[SlamLoopResult, SlamLoopResult]) -> None:
    """The issue's acceptance: ATE <= 5 cm with loop closure, measurably worse without it, IoU >= 0.85."""
    on, off = hard
    _show("hard", on, off)
    assert all(g.succeeded for g in on.goals), [g.detail for g in on.goals]
    assert on.odom_ate_rmse > 0.5
    assert on.loop_closures >= 3
    assert on.ate_rmse <= 0.05, on.ate_rmse
    assert on.iou >= 0.85, on.iou
    # measurably worse: >= 25 % and >= 5 mm more (seed 0: 1.7 cm on vs 2.5 cm off)
    assert off.ate_rmse >= 1.25 * on.ate_rmse and off.ate_rmse - on.ate_rmse >= 0.005, (on.ate_rmse, off.ate_rmse)
