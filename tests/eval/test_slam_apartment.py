"""SLAM on MuJoCo scans: the apartment loop with drifting odometry, scored against ground truth.

IoU definition (slam_service.core.occupied_iou): occupied cells (>= 65) of the SLAM map vs the scene
rasterised at the SLAM resolution with only obstacles that reach the lidar plane (height >= lidar mount z),
a cell counts as matched if the other set has an occupied cell within 1 cell (Chebyshev), and ground-truth
walls the map never observed (no known cell within 1 cell) are left out.
"""

from __future__ import annotations

import pytest

from robonix_eval.slam_loop import SlamLoopResult, run_slam_loop


@pytest.fixture(scope="module")
def lc_on() -> SlamLoopResult:
    return run_slam_loop("apartment", loop_closure=True, seed=0)


@pytest.fixture(scope="module")
def lc_off() -> SlamLoopResult:
    return run_slam_loop("apartment", loop_closure=False, seed=0)


def test_route_driven_and_odometry_drifts(lc_on: SlamLoopResult) -> None:
    assert all(g.succeeded for g in lc_on.goals), [g.detail for g in lc_on.goals]
    assert lc_on.odom_ate_rmse > 0.15  # the drift SLAM has to remove is real
    assert lc_on.loop_closures >= 3


def test_ate_and_iou_with_loop_closure(lc_on: SlamLoopResult) -> None:
    assert lc_on.ate_rmse <= 0.05, lc_on.ate_rmse
    assert lc_on.iou >= 0.85, lc_on.iou


def test_ate_and_iou_without_loop_closure(lc_off: SlamLoopResult) -> None:
    assert lc_off.loop_closures == 0
    assert lc_off.ate_rmse <= 0.05 and lc_off.iou >= 0.85


@pytest.mark.xfail(strict=True, reason=(
    "slam_service core: on MuJoCo scans sequential matching alone reaches ~5 mm ATE, and the loop matcher "
    "accepts a few closures 3-7 cm off (responses 0.58-0.75, overconfident covariance), so LC on is worse "
    "(~25 mm) than LC off; see the eval report"))
def test_loop_closure_improves_ate(lc_on: SlamLoopResult, lc_off: SlamLoopResult) -> None:
    assert lc_off.ate_rmse > 1.2 * lc_on.ate_rmse, (lc_on.ate_rmse, lc_off.ate_rmse)
