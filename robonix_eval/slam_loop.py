"""SLAM quality on a MuJoCo scene: drive a scripted loop through named waypoints and score the map.

The robot is driven by the navigator on the ground-truth map with the true pose (so the route does not
depend on the SLAM result being scored), while SLAM integrates the sim's drifting odometry and lidar.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from hal_panda_mobile.sim import LidarNoise, OdomNoise
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse, occupied_iou

from .pipeline import GoalResult, Pipeline, PipelineOptions

# Routes that revisit the start area after a long detour, so loop closure has something to close.
ROUTES: dict[str, tuple[str, ...]] = {
    "apartment": ("bedroom", "living", "kitchen", "bedroom_2", "bathroom", "bedroom_2", "kitchen", "living"),
    "warehouse": ("aisle_1", "cross", "aisle_2", "dock", "top_aisle", "aisle_3", "aisle_1"),
    "office": ("office_s0", "office_n1", "corridor_east", "office_s3", "office_n0", "office_s0"),
    "kitchen": ("island_east", "fridge", "pantry", "dining", "island_east"),
}


# "hard": where loop closure has something to fix. Odometry drifts ~2.5x the realistic profile and SLAM
# gets a cheap lidar's view of the scans: every 3rd beam (120 of 360) with 2.5 cm range noise in total.
# Only SLAM's copy is degraded; the navigator (on ground truth here) keeps the sim's 1 cm scans.
HARD_ODOM = OdomNoise(v_scale_std=0.05, w_scale_std=0.05, v_add_std=0.01, w_add_std=0.02, scale_bias=0.02,
                      w_bias=0.01)
HARD_BEAM_STEP = 3
HARD_EXTRA_RANGE_NOISE = 0.023  # on top of the sim's 1 cm: sqrt(0.01^2 + 0.023^2) = 2.5 cm


@dataclass
class SlamLoopResult:
    scene: str
    loop_closure: bool
    ate_rmse: float  # m, SLAM nodes vs ground truth, no alignment (map frame starts at the true start)
    odom_ate_rmse: float  # m, raw odometry at the same stamps: what SLAM had to correct
    iou: float  # occupied-cell IoU, 1-cell tolerance, observed walls only, lidar-plane obstacles
    nodes: int
    scans: int
    loop_closures: int
    slam_seconds: float  # wall s inside SlamEngine.process (informative)
    optimize_times: list[float] = field(default_factory=list)
    goals: list[GoalResult] = field(default_factory=list)

    @property
    def scans_per_s(self) -> float:
        return self.scans / self.slam_seconds if self.slam_seconds > 0 else float("nan")


class _TimedSlam:
    """Wraps SlamEngine.process to accumulate its wall time without touching the engine."""

    def __init__(self, pipe: Pipeline) -> None:
        self.seconds = 0.0
        inner = pipe.slam.process

        def timed(*args: object, **kwargs: object):  # type: ignore[no-untyped-def]
            t0 = time.perf_counter()
            out = inner(*args, **kwargs)  # type: ignore[arg-type]
            self.seconds += time.perf_counter() - t0
            return out

        pipe.slam.process = timed  # type: ignore[method-assign]


class _Degrade:
    """Wraps SlamEngine.process to hand SLAM a decimated, noisier copy of each scan (seeded)."""

    def __init__(self, engine: SlamEngine, step: int, extra_noise: float, seed: int) -> None:
        self.rng = np.random.default_rng(seed + 7919)
        inner = engine.process

        def degraded(scan: Scan, odom: object, stamp: float | None = None):  # type: ignore[no-untyped-def]
            r = np.asarray(scan.ranges, dtype=np.float64)[::step].copy()
            ok = np.isfinite(r)
            r[ok] += self.rng.normal(0.0, extra_noise, int(ok.sum()))
            return inner(dataclasses.replace(scan, ranges=r.astype(np.float32),
                                             angle_increment=scan.angle_increment * step), odom, stamp)

        engine.process = degraded  # type: ignore[method-assign]


def run_slam_loops(scene: str = "apartment", *, seed: int = 0, hard: bool = False,
                   route: Sequence[str] | None = None, options: PipelineOptions | None = None
                   ) -> tuple[SlamLoopResult, SlamLoopResult]:
    """(LC on, LC off) from ONE drive: the route does not depend on SLAM (navigator on ground truth), so a
    second engine with loop closure off is fed the very same scans and odometry. ``hard``: see HARD_*."""
    base = options or PipelineOptions()
    over: dict[str, object] = {"scene": scene, "seed": seed, "loop_closure": True, "nav_map": "ground_truth"}
    if hard:
        over["odom_noise"] = HARD_ODOM
        over["lidar_noise"] = LidarNoise(noise_std=0.01)
    pipe = Pipeline(PipelineOptions(**{**base.__dict__, **over}))
    cfg = pipe.slam.config
    off = SlamEngine(SlamConfig.from_dict({**cfg.to_dict(), "loop_closure": False}))
    if hard:
        _Degrade(pipe.slam, HARD_BEAM_STEP, HARD_EXTRA_RANGE_NOISE, seed)
        _Degrade(off, HARD_BEAM_STEP, HARD_EXTRA_RANGE_NOISE, seed)  # same seed: identical scans
    timer = _TimedSlam(pipe)
    off_seconds = [0.0]
    inner = pipe.slam.process

    def both(*args: object, **kwargs: object):  # type: ignore[no-untyped-def]
        t0 = time.perf_counter()
        off.process(*args, **kwargs)  # type: ignore[arg-type]
        off_seconds[0] += time.perf_counter() - t0
        return inner(*args, **kwargs)  # type: ignore[arg-type]

    pipe.slam.process = both  # type: ignore[method-assign]
    wps = pipe.sim.scene.waypoints
    goals = [(float(wps[n][0]), float(wps[n][1]), 0.0) for n in list(route or ROUTES[scene])]
    results = pipe.run_goals(goals)
    truth = pipe.ground_truth_grid(min_height=pipe.robot.lidar.mount[2])
    out = []
    for eng, lc, secs in ((pipe.slam, True, timer.seconds), (off, False, off_seconds[0])):
        stamps = [round(float(t), 6) for t in eng.node_stamps()]
        gt = np.array([pipe.gt_at_scan[t] for t in stamps]).reshape(-1, 3)
        odom = np.array([pipe.odom_at_scan[t] for t in stamps]).reshape(-1, 3)
        est = eng.trajectory()
        out.append(SlamLoopResult(
            scene=scene, loop_closure=lc, ate_rmse=ate_rmse(est, gt), odom_ate_rmse=ate_rmse(odom, gt),
            iou=occupied_iou(eng.map(), truth, tolerance_cells=1, observed_only=True), nodes=len(est),
            scans=eng.stats.scans_received, loop_closures=eng.stats.loop_closures, slam_seconds=secs,
            optimize_times=list(eng.optimize_times), goals=results))
    return out[0], out[1]


def run_slam_loop(scene: str = "apartment", *, loop_closure: bool = True, seed: int = 0,
                  route: Sequence[str] | None = None, options: PipelineOptions | None = None,
                  hard: bool = False) -> SlamLoopResult:
    """Drive ``route`` (waypoint names; default ROUTES[scene]) and score SLAM against ground truth."""
    on, off = run_slam_loops(scene, seed=seed, hard=hard, route=route, options=options)
    return on if loop_closure else off

