"""SLAM on MuJoCo scans: a SCRIPTED apartment loop with drifting odometry, scored against ground truth.

The drive (robonix_eval.slam_loop.LOOPS["apartment"], ~58 m through every room and doorway, back to the
start) is a holonomic P-controller on the true pose, independent of the navigation stack; each drive
feeds two engines (loop closure on and off) identical scans and odometry. Two settings:
- realistic: the sim's realistic drift, 360 beams with 1 cm noise. Loop closure must not hurt.
- hard (issue 5 acceptance): ~2.5x the drift (odometry ATE ~5 m), SLAM sees 120 beams with 2.5 cm
  noise and 3 % dropouts. ATE with loop closure <= 5 cm and IoU >= 0.85 on every seed.

Measured (bench/slam_suite.py, seeds 0-4, hard, ATE cm LC on / off): 1.27/2.17, 1.47/5.08, 2.62/3.63,
1.66/2.65, 1.40/2.82. LC off is worse on every seed, by 1.4-3.5x. How much worse depends on the seed: the
scan-matching chain alone stays within a few cm in a room this size, so the margin comes from loop edges
being precise (REFINE_NEIGHBOURS in slam_service.core.matcher), not from a large drift to undo.

IoU definition (slam_service.core.occupied_iou): occupied cells (>= 65) of the SLAM map vs the scene
rasterised at the SLAM resolution with only obstacles that reach the lidar plane (height >= lidar mount z),
a cell counts as matched if the other set has an occupied cell within 1 cell (Chebyshev), and ground-truth
walls the map never observed (no known cell within 1 cell) are left out.
"""

from __future__ import annotations

import pytest

from robonix_eval.slam_loop import SlamLoopResult, run_slam_loops

# ~58 m scripted drives for every seed (109 s of fixture setup at load ~10): the slow suite of .ci/run
pytestmark = pytest.mark.slow

HARD_SEEDS = (0, 1, 2)
Pair = tuple[SlamLoopResult, SlamLoopResult]


@pytest.fixture(scope="module")
def realistic() -> Pair:
    return run_slam_loops("apartment", seed=0)


@pytest.fixture(scope="module")
def hard() -> dict[int, Pair]:
    return {seed: run_slam_loops("apartment", seed=seed, hard=True) for seed in HARD_SEEDS}


def _show(name: str, on: SlamLoopResult, off: SlamLoopResult) -> None:
    print(f"\n{name} seed {on.seed}: ATE LC on {on.ate_rmse * 100:.2f} cm ({on.loop_closures} closures), LC off "
          f"{off.ate_rmse * 100:.2f} cm, odometry {on.odom_ate_rmse * 100:.1f} cm; "
          f"IoU on {on.iou:.3f} off {off.iou:.3f}")


def _drive_ok(on: SlamLoopResult) -> None:
    d = on.drive
    assert d.completed, (d.reached, d.waypoints)
    assert d.collisions == 0
    assert d.max_track_error < 0.05, d
    assert d.path_length > 50.0, d


def test_scripted_drive_and_odometry_drift(realistic: Pair, hard: dict[int, Pair]) -> None:
    on, off = realistic
    _drive_ok(on)
    assert on.odom_ate_rmse > 0.5  # the drift SLAM has to remove is real
    assert on.loop_closures >= 3
    assert off.loop_closures == 0
    for on, _ in hard.values():
        _drive_ok(on)
        assert on.odom_ate_rmse > 2.0


def test_realistic_loop_closure_is_never_harmful(realistic: Pair) -> None:
    on, off = realistic
    _show("realistic", on, off)
    assert on.ate_rmse <= 0.05, (on.ate_rmse, on.iou)
    assert on.iou >= 0.85, (on.ate_rmse, on.iou)
    assert off.ate_rmse <= 0.05, (off.ate_rmse, off.iou)
    assert off.iou >= 0.85, (off.ate_rmse, off.iou)
    assert on.ate_rmse <= off.ate_rmse + 0.01  # verified closures: no worse than scan matching alone


@pytest.mark.parametrize("seed", HARD_SEEDS)
def test_hard_acceptance_ate_and_iou(hard: dict[int, Pair], seed: int) -> None:
    """The issue's acceptance: ATE <= 5 cm with loop closure and IoU >= 0.85 after the loop."""
    on, off = hard[seed]
    _show("hard", on, off)
    assert on.loop_closures >= 3
    assert on.ate_rmse <= 0.05, on.ate_rmse
    assert on.iou >= 0.85, on.iou


@pytest.mark.parametrize("seed", HARD_SEEDS)
def test_hard_loop_closure_measurably_better(hard: dict[int, Pair], seed: int) -> None:
    """The issue's other half: the same drive with loop closure off is measurably worse."""
    on, off = hard[seed]
    assert off.ate_rmse >= 1.2 * on.ate_rmse, (on.ate_rmse, off.ate_rmse)
    assert off.ate_rmse - on.ate_rmse >= 0.005, (on.ate_rmse, off.ate_rmse)
