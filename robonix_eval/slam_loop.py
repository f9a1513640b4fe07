"""SLAM quality on a MuJoCo scene: drive a scripted loop through named waypoints and score the map.

The robot is driven by the navigator on the ground-truth map with the true pose (so the route does not
depend on the SLAM result being scored), while SLAM integrates the sim's drifting odometry and lidar.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from slam_service.core import ate_rmse, occupied_iou

from .pipeline import GoalResult, Pipeline, PipelineOptions

# Routes that revisit the start area after a long detour, so loop closure has something to close.
ROUTES: dict[str, tuple[str, ...]] = {
    "apartment": ("bedroom", "living", "kitchen", "bedroom_2", "bathroom", "bedroom_2", "kitchen", "living"),
    "warehouse": ("aisle_1", "cross", "aisle_2", "dock", "top_aisle", "aisle_3", "aisle_1"),
    "office": ("office_s0", "office_n1", "corridor_east", "office_s3", "office_n0", "office_s0"),
    "kitchen": ("island_east", "fridge", "pantry", "dining", "island_east"),
}


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


def run_slam_loop(scene: str = "apartment", *, loop_closure: bool = True, seed: int = 0,
                  route: Sequence[str] | None = None, options: PipelineOptions | None = None) -> SlamLoopResult:
    """Drive ``route`` (waypoint names; default ROUTES[scene]) and score SLAM against ground truth."""
    base = options or PipelineOptions()
    opts = PipelineOptions(**{**base.__dict__, "scene": scene, "seed": seed, "loop_closure": loop_closure,
                              "nav_map": "ground_truth"})
    pipe = Pipeline(opts)
    timer = _TimedSlam(pipe)
    wps = pipe.sim.scene.waypoints
    names = list(route or ROUTES[scene])
    goals = [(float(wps[n][0]), float(wps[n][1]), 0.0) for n in names]
    results = pipe.run_goals(goals)
    est, gt, odom = pipe.slam_trajectory()
    truth = pipe.ground_truth_grid(min_height=pipe.robot.lidar.mount[2])
    return SlamLoopResult(
        scene=scene, loop_closure=loop_closure, ate_rmse=ate_rmse(est, gt), odom_ate_rmse=ate_rmse(odom, gt),
        iou=occupied_iou(pipe.slam.map(), truth, tolerance_cells=1, observed_only=True),
        nodes=len(est), scans=pipe.slam.stats.scans_received, loop_closures=pipe.slam.stats.loop_closures,
        slam_seconds=timer.seconds, optimize_times=list(pipe.slam.optimize_times), goals=results)

