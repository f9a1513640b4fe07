"""Sim + SLAM core + navigation core stepped together in one process, on sim time, deterministically.

Rates follow the deployed system: physics 500 Hz, odometry 50 Hz (the sim's own odometry ticks), lidar
10 Hz into SLAM, navigator 20 Hz. The navigator sees what the provider would see: the latest odometry
message (not the true pose), ``pose_map = map→odom ⊕ odom``, the SLAM grid when it changed (rate
capped), and every scan with the lidar mount as sensor pose. No threads and no wall clock in the loop:
one seed gives one result.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from hal_panda_mobile.files import load_robot_description, load_scene
from hal_panda_mobile.sim import LidarNoise, OdomNoise, OdomState, PandaMobileSim
from nav2_wrapper.core import Command, Navigator
from nav2_wrapper.core.mppi import MppiConfig
from nav2_wrapper.core.navigator import TERMINAL
from nav2_wrapper.params import load_params
from robonix_common.geometry import Pose2D, compose
from robonix_common.grid import GridMap
from robonix_common.scan import Scan
from slam_service.core import SlamConfig, SlamEngine

from .clearance import RESOLUTION_M as CLEARANCE_RESOLUTION
from .clearance import ClearanceField
from .metrics import ShortestPaths, yaw_error

MapSource = Literal["slam", "ground_truth"]


@dataclass(frozen=True)
class PipelineOptions:
    """What varies between evaluation runs; defaults are the deployed sim profile with realistic drift."""

    scene: str = "apartment"
    seed: int = 0
    odom_noise: OdomNoise = field(default_factory=OdomNoise.realistic)
    lidar_noise: LidarNoise | None = field(default_factory=lambda: LidarNoise(noise_std=0.01))
    nav_map: MapSource = "slam"  # "ground_truth": known map and true pose (SLAM still runs, for scoring)
    loop_closure: bool = True
    slam_config: SlamConfig | None = None
    nav_profile: str = "sim"
    controller: Literal["profile", "pursuit", "mppi"] = "profile"  # override the profile's controller plugin
    physics_hz: float = 500.0
    odom_hz: float = 50.0
    scan_hz: float = 10.0
    control_hz: float = 20.0
    map_period: float = 1.0  # s of sim time between grids handed to the navigator (the /map rate cap)
    settle_time: float = 0.5  # s the robot is left to stop after a goal ends, before the final pose is scored


@dataclass
class GoalResult:
    """One goal's outcome, scored against ground truth."""

    goal: Pose2D
    start: Pose2D
    state: str  # SUCCEEDED / FAILED / CANCELED / TIMEOUT
    detail: str
    time: float  # s of sim time from send to a terminal state
    path_length: float  # m driven (ground truth)
    shortest_length: float  # m, shortest feasible path on the ground-truth grid (NaN: none)
    final_error_xy: float  # m, ground truth after settling
    final_error_yaw: float  # rad
    within_tolerance: bool
    collisions: int
    recoveries: int
    plan_times: list[float] = field(default_factory=list)  # wall s per planner call (informative only)
    final_speed: float = 0.0  # m/s ground truth after settling
    closest_m: float = math.nan  # the true footprint's closest approach to the true obstacles while driving (m)

    @property
    def reached(self) -> bool:
        """Navigation reported the goal reached (contacts aside)."""
        return self.state == "SUCCEEDED"

    @property
    def succeeded(self) -> bool:
        """Reached without touching anything: a contact during the goal fails it in every suite's score."""
        return self.reached and self.collisions == 0

    @property
    def path_ratio(self) -> float:
        return self.path_length / self.shortest_length if self.shortest_length > 0 else math.nan

    def to_dict(self) -> dict[str, object]:
        d = {k: v for k, v in self.__dict__.items() if k != "plan_times"}
        d["plan_ms_median"] = 1e3 * statistics.median(self.plan_times) if self.plan_times else math.nan
        d["path_ratio"] = self.path_ratio
        d["reached"] = self.reached
        d["succeeded"] = self.succeeded
        return d


class Pipeline:
    """Owns one sim, one SlamEngine and one Navigator and advances them on a shared sim clock."""

    def __init__(self, options: PipelineOptions | None = None) -> None:
        o = self.options = options or PipelineOptions()
        self.robot = load_robot_description()
        self.sim = PandaMobileSim(self.robot, load_scene(o.scene), seed=o.seed, odom_noise=o.odom_noise,
                                  lidar_noise=o.lidar_noise, timestep=1.0 / o.physics_hz, odom_rate_hz=o.odom_hz)
        cfg = o.slam_config or SlamConfig()
        if cfg.loop_closure != o.loop_closure:
            cfg = SlamConfig.from_dict({**cfg.to_dict(), "loop_closure": o.loop_closure})
        self.slam = SlamEngine(cfg)
        self.params = load_params(o.nav_profile)
        if o.controller == "mppi" and self.params.config.mppi is None:
            self.params.config.mppi = MppiConfig(seed=o.seed)
        elif o.controller == "pursuit":
            self.params.config.mppi = None
        self.nav = Navigator(self.params.config)
        self.plan_times: list[float] = []
        self._wrap_planner()
        mx, my, _, myaw = self.robot.lidar.mount
        self.mount: Pose2D = (mx, my, myaw)
        dt = self.sim.timestep
        self._every = {k: max(1, round(1.0 / (hz * dt)))
                       for k, hz in (("odom", o.odom_hz), ("scan", o.scan_hz), ("ctrl", o.control_hz))}
        self._next = dict(self._every)
        self._step = 0
        self.odom: OdomState = self.sim.odometry()
        self.map_to_odom: Pose2D = (0.0, 0.0, 0.0)
        self._scan: Scan | None = None
        self._sensor_pose: Pose2D | None = None
        self._map_dirty = False
        self._map_sent_at = -math.inf
        self.gt_at_scan: dict[float, Pose2D] = {}  # sim stamp -> true pose, for trajectory scoring
        self.odom_at_scan: dict[float, Pose2D] = {}  # sim stamp -> odometry pose (what SLAM was given)
        self.last_cmd = Command(0.0, 0.0, 0.0, "IDLE", "idle")
        self.driven = 0.0  # m of ground-truth travel since construction
        self._last_xy = self.sim.ground_truth()[:2]
        self._gt_grid: GridMap | None = None
        self._shortest: ShortestPaths | None = None
        self._gt_version = -1
        self._clearance: tuple[int, ClearanceField] | None = None   # (obstacle count, field) for closest_m
        self.hooks: list[Callable[[Pipeline], None]] = []  # called after every control tick

    # ---------------------------------------------------------------- plumbing
    def _wrap_planner(self) -> None:
        """Time each global plan (wall clock, reported only: it never feeds back into the run)."""
        inner = self.nav.planner.plan

        def timed(*args: object, **kwargs: object):  # type: ignore[no-untyped-def]
            t0 = time.perf_counter()
            res = inner(*args, **kwargs)  # type: ignore[arg-type]
            self.plan_times.append(time.perf_counter() - t0)
            return res

        self.nav.planner.plan = timed  # type: ignore[method-assign]

    @property
    def time(self) -> float:
        return self.sim.time

    def ground_truth_pose(self) -> Pose2D:
        x, y, yaw, *_ = self.sim.ground_truth()
        return (x, y, yaw)

    def pose_map(self) -> Pose2D:
        """The robot pose the navigator uses: SLAM's map→odom composed with the latest odometry message."""
        if self.options.nav_map == "ground_truth":
            return self.ground_truth_pose()
        p = compose(self.map_to_odom, (self.odom.x, self.odom.y, self.odom.yaw))
        return (float(p[0]), float(p[1]), float(p[2]))

    def ground_truth_grid(self, min_height: float = 0.0) -> GridMap:
        return self.sim.ground_truth_grid(self.slam.config.resolution, min_height=min_height)

    def shortest_path_length(self, start: Sequence[float], goal: Sequence[float]) -> float:
        version = len(self.sim.scene_info()["obstacles"])
        if self._shortest is None or version != self._gt_version:
            self._shortest = ShortestPaths(self.ground_truth_grid(), self.params.config.global_costmap.footprint)
            self._gt_version = version
        return self._shortest.length(start, goal)

    # ---------------------------------------------------------------- stepping
    def step(self) -> None:
        """Advance to the next event (odometry, scan or control tick) and handle it."""
        nxt = min(self._next.values())
        self.sim.step(nxt - self._step)
        self._step = nxt
        if self._next["odom"] == nxt:
            self._next["odom"] += self._every["odom"]
            self.odom = self.sim.odometry()
        if self._next["scan"] == nxt:
            self._next["scan"] += self._every["scan"]
            self._on_scan()
        if self._next["ctrl"] == nxt:
            self._next["ctrl"] += self._every["ctrl"]
            self._on_control()

    def run_for(self, seconds: float) -> None:
        end = self._step + round(seconds / self.sim.timestep)
        while min(self._next.values()) <= end:
            self.step()

    def _on_scan(self) -> None:
        s = self.sim.scan()
        odom = self.sim.odometry()  # scan ticks fall on odometry ticks: this is the message at the stamp
        self.gt_at_scan[round(s.stamp, 6)] = self.ground_truth_pose()
        self.odom_at_scan[round(s.stamp, 6)] = (odom.x, odom.y, odom.yaw)
        u = self.slam.process(Scan(s.ranges, s.angle_min, s.angle_increment, s.range_min, s.range_max, s.stamp,
                                   self.mount, s.frame_id), (odom.x, odom.y, odom.yaw), s.stamp)
        self.map_to_odom = (float(u.map_to_odom[0]), float(u.map_to_odom[1]), float(u.map_to_odom[2]))
        self._map_dirty |= u.map_changed
        self._scan = Scan(s.ranges.astype(np.float64), s.angle_min, s.angle_increment, s.range_min, s.range_max)
        base = (compose(self.map_to_odom, (odom.x, odom.y, odom.yaw)) if self.options.nav_map == "slam"
                else self.ground_truth_pose())
        sp = compose(base, self.mount)
        self._sensor_pose = (float(sp[0]), float(sp[1]), float(sp[2]))

    def _grid_for_nav(self, now: float) -> GridMap | None:
        if self.options.nav_map == "ground_truth":
            version = len(self.sim.scene_info()["obstacles"])
            if version != self._gt_version or self._gt_grid is None:
                self._gt_grid = self.ground_truth_grid()
                self._gt_version = version
                self._shortest = None
                return self._gt_grid
            return None
        if self._map_dirty and now - self._map_sent_at >= self.options.map_period - 1e-9:
            self._map_dirty = False
            self._map_sent_at = now
            return self.slam.map()
        return None

    def _on_control(self) -> None:
        now = self.time
        pose = self.pose_map()
        vel = (self.odom.vx, self.odom.vy, self.odom.wz)
        if self.options.nav_map == "ground_truth":
            vel = tuple(self.sim.ground_truth()[3:])  # type: ignore[assignment]
        cmd = self.nav.tick(now, pose, vel, grid=self._grid_for_nav(now), scan=self._scan,
                            sensor_pose=self._sensor_pose)
        self._scan = None
        self.last_cmd = cmd
        self.sim.set_cmd_vel(cmd.vx, cmd.vy, cmd.wz, stamp=now)
        x, y = self.sim.ground_truth()[:2]
        self.driven += math.hypot(x - self._last_xy[0], y - self._last_xy[1])
        self._last_xy = (x, y)
        for hook in self.hooks:
            hook(self)

    # ---------------------------------------------------------------- goals
    def default_timeout(self, shortest: float) -> float:
        """Generous sim-time budget: three times the shortest path at cruise speed, plus recoveries."""
        speed = self.params.config.controller.desired_linear_vel
        return 60.0 + 3.0 * (shortest if math.isfinite(shortest) else 10.0) / speed

    def navigate(self, x: float, y: float, yaw: float, timeout: float | None = None) -> GoalResult:
        """Send one goal, step until it ends (or the sim-time budget runs out), settle, and score it."""
        start = self.ground_truth_pose()
        shortest = self.shortest_path_length(start, (x, y))
        budget = timeout if timeout is not None else self.default_timeout(shortest)
        t0, d0, n_plan = self.time, self.driven, len(self.plan_times)
        n_col = len(self.sim.collisions())
        rec = self.nav.navigate(x, y, yaw, t0)
        track = [start]
        while rec.state not in TERMINAL and self.time - t0 < budget:
            self.step()
            track.append(self.ground_truth_pose())
        state, detail = rec.state, rec.detail
        if state not in TERMINAL:
            self.nav.cancel(self.time, rec.run_id)
            state, detail = "TIMEOUT", f"no terminal state within {budget:.0f} s: {detail}"
        elapsed = self.time - t0
        self.run_for(self.options.settle_time)
        gx, gy, gyaw, vx, vy, _ = self.sim.ground_truth()
        gc = self.params.config.goal_checker
        exy, eyaw = math.hypot(gx - x, gy - y), yaw_error(gyaw, yaw)
        return GoalResult(
            goal=(x, y, yaw), start=start, state=state, detail=detail, time=elapsed,
            path_length=self.driven - d0, shortest_length=shortest, final_error_xy=exy, final_error_yaw=eyaw,
            within_tolerance=exy <= gc.xy_goal_tolerance and eyaw <= gc.yaw_goal_tolerance,
            collisions=len(self.sim.collisions()) - n_col, recoveries=rec.recoveries,
            plan_times=self.plan_times[n_plan:], final_speed=math.hypot(vx, vy),
            closest_m=self._closest_approach(track))

    def _closest_approach(self, track: Sequence[Pose2D]) -> float:
        """The smallest clearance of the true footprint to the true obstacles over ``track`` (m)."""
        version = len(self.sim.scene_info()["obstacles"])
        if self._clearance is None or self._clearance[0] != version:
            grid = self.sim.ground_truth_grid(CLEARANCE_RESOLUTION, overlap=False)
            self._clearance = (version, ClearanceField.from_grid(grid, self.robot.footprint))
        closest = self._clearance[1].closest(track)
        return closest.clearance_m if closest is not None else math.nan

    def run_goals(self, goals: Sequence[Sequence[float]], warmup: float = 0.5) -> list[GoalResult]:
        """Goals in sequence from wherever the previous one left the robot (the map keeps growing)."""
        if self.time < warmup:
            self.run_for(warmup - self.time)
        return [self.navigate(float(g[0]), float(g[1]), float(g[2]) if len(g) > 2 else 0.0) for g in goals]

    # ---------------------------------------------------------------- SLAM scoring
    def slam_trajectory(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(estimated node poses, true poses, raw odometry poses) at the SLAM node stamps, each (N, 3)."""
        stamps = [round(float(t), 6) for t in self.slam.node_stamps()]
        gt = np.array([self.gt_at_scan[t] for t in stamps]).reshape(-1, 3)
        odom = np.array([self.odom_at_scan[t] for t in stamps]).reshape(-1, 3)
        return self.slam.trajectory(), gt, odom
