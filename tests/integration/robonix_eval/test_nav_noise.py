"""Navigation under realistic lidar noise (2–3 cm range noise, 2–5 % dropouts) and through a tight gap, in the
MuJoCo loop. Both used to end in "controller found no collision-free command"; everything here is sim time."""

from __future__ import annotations

import pytest

from hal_panda_mobile.sim import LidarNoise
from robonix_eval.pipeline import Pipeline, PipelineOptions
from robonix_eval.slam_loop import ROUTES

# x, y, sx, sy: dropped on the office corridor (clear y 5.05..6.95) against one wall, leaving a 0.8 m gap
GAP_BOXES = {"south": (8.0, 5.6, 0.6, 1.1), "north": (8.0, 6.4, 0.6, 1.1)}


# The whole-route drives on the ground-truth map are long: the slow suite of .ci/run; the noisiest lidar on
# the SLAM map stays in the fast suite.
@pytest.mark.parametrize(("std", "dropout", "nav_map"), [
    pytest.param(0.02, 0.02, "ground_truth", marks=pytest.mark.slow),
    pytest.param(0.03, 0.05, "ground_truth", marks=pytest.mark.slow),
    (0.03, 0.05, "slam")])
def test_apartment_route_with_noisy_lidar(std: float, dropout: float, nav_map: str) -> None:
    pipe = Pipeline(PipelineOptions(scene="apartment", seed=0, nav_map=nav_map,  # type: ignore[arg-type]
                                    lidar_noise=LidarNoise(noise_std=std, dropout_prob=dropout)))
    wps = pipe.sim.scene.waypoints
    results = pipe.run_goals([(float(wps[n][0]), float(wps[n][1]), 0.0) for n in ROUTES["apartment"]])
    # on the SLAM map the navigator stops at the tolerance by its own estimate; localisation error may add to it
    slack = 0.0 if nav_map == "ground_truth" else 0.1
    tol = pipe.params.config.goal_checker.xy_goal_tolerance + slack
    for r in results:
        assert r.state == "SUCCEEDED", (r.goal, r.detail)
        assert r.collisions == 0, (r.goal, r.collisions)
        assert r.final_error_xy <= tol, (r.goal, r.final_error_xy)
    assert sum(r.recoveries for r in results) <= 2


@pytest.mark.parametrize(("side", "noise"), [("south", 0.01), ("north", 0.03)])
def test_passes_a_gap_beside_a_dropped_box(side: str, noise: float) -> None:
    box = GAP_BOXES[side]
    pipe = Pipeline(PipelineOptions(scene="office", seed=0, lidar_noise=LidarNoise(noise_std=noise,
                                                                                   dropout_prob=0.02)))
    dropped: list[float] = []

    def drop_box(p: Pipeline) -> None:
        if not dropped and p.ground_truth_pose()[0] > box[0] - 1.5:   # 1.5 m ahead: already lined up
            p.sim.spawn_box("dropped", *box)
            dropped.append(p.time)

    pipe.hooks.append(drop_box)
    r = pipe.run_goals([(14.5, 6.0, 0.0)])[0]
    assert dropped, "the robot never came near the drop point"
    assert r.state == "SUCCEEDED", r.detail
    assert r.collisions == 0
    assert r.within_tolerance
