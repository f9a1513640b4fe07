"""SLAM quality on a MuJoCo scene: drive a scripted loop and score the trajectory and the map.

The drive is independent of the navigation stack (no nav2_wrapper here): a deterministic holonomic
P-controller on the ground-truth pose follows a fixed polyline of waypoints (``LOOPS``) at a fixed speed,
turning in place at each corner to face the next leg. SLAM integrates the sim's drifting odometry and
lidar, so the route cannot depend on the SLAM result being scored, and one drive feeds two engines
(loop closure on and off) the very same scans and odometry. Same seed, same numbers.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from hal_panda_mobile.files import load_robot_description, load_scene
from hal_panda_mobile.sim import LidarNoise, OdomNoise, PandaMobileSim
from robonix_common.grid import GridMap
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse, occupied_iou

# Named-waypoint routes for the navigation evaluations (tests/integration/robonix_eval/test_nav_noise.py,
# bench/nav_suite).
ROUTES: dict[str, tuple[str, ...]] = {
    "apartment": ("bedroom", "living", "kitchen", "bedroom_2", "bathroom", "bedroom_2", "kitchen", "living"),
    "warehouse": ("aisle_1", "cross", "aisle_2", "dock", "top_aisle", "aisle_3", "aisle_1"),
    "office": ("office_s0", "office_n1", "corridor_east", "office_s3", "office_n0", "office_s0"),
    "kitchen": ("island_east", "fridge", "pantry", "dining", "island_east"),
}

# A waypoint is (x, y) or (x, y, heading): the robot turns in place at the previous waypoint to face the
# leg (or to ``heading`` if given: a holonomic sidestep where there is no room to turn), then drives it.
Waypoint = tuple[float, float] | tuple[float, float, float]
_UP, _DOWN = math.pi / 2, -math.pi / 2

# Scripted SLAM loops: long excursions that come back through already-mapped rooms and end at the start.
# Apartment (12 x 10 m, start (2.5, 4.0)): bedroom lap, living -> hall through the east doorway (y 3.95-4.95),
# lap round the dining table, bedroom_2 through the 0.9 m doorway at x 8.5, bathroom (doorway y 7.05-8.15)
# lap, back out the same way, living lap, start. ~56 m; every turn-in-place point has >= 0.43 m (the
# footprint's circumradius) of clearance, legs keep >= 0.2 m (collision events are counted and tested).
LOOPS: dict[str, tuple[Waypoint, ...]] = {
    "apartment": (
        (3.8, 4.0), (3.8, 5.2), (2.6, 5.2),  # straight out along the start heading first
        (2.6, 7.0), (4.2, 7.0), (4.2, 8.6), (2.8, 8.6), (2.6, 7.0),  # bedroom lap
        (2.6, 4.45), (6.0, 4.45),  # living -> hall
        (6.0, 1.6), (9.0, 1.6), (9.0, 4.0),  # round the dining table
        (8.5, 4.0), (8.5, 6.2), (7.6, 6.2, _UP),  # bedroom_2 doorway, sidestep clear of the x = 9 wall
        (7.5, 7.55), (10.8, 7.55), (10.8, 6.3), (9.6, 6.3), (9.6, 7.55), (7.5, 7.55),  # bathroom lap
        (7.6, 6.2), (8.5, 6.2, _DOWN), (8.5, 4.0),  # back out of bedroom_2
        (6.0, 4.45), (1.4, 4.45), (1.4, 2.9), (4.2, 2.9), (2.5, 4.0),  # hall -> living lap -> start
    ),
    # Warehouse (20 x 14 m, start (2, 4)): twice round the shelf block, a genuine cycle (~42 m per lap).
    "warehouse": ((3.0, 4.0), (17.0, 4.0), (17.0, 10.0), (3.0, 10.0), (3.0, 4.0),
                  (17.0, 4.0), (17.0, 10.0), (3.0, 10.0), (3.0, 4.0), (2.0, 4.0)),
}


@dataclass(frozen=True)
class LoopSetting:
    """Sensor quality and drive parameters of one SLAM-loop evaluation."""

    name: str
    odom_noise: OdomNoise
    lidar_noise: LidarNoise  # the sim's lidar (SLAM sees it decimated by beam_step)
    beam_step: int = 1  # SLAM gets every beam_step-th beam (360 / beam_step beams)
    max_range: float | None = None  # m: a shorter-range lidar (longer returns become "no return", +inf)
    speed: float = 0.4  # m/s along each leg
    slam_config: SlamConfig | None = None


# "realistic": the sim's realistic odometry drift, the full 360-beam lidar with 1 cm noise.
REALISTIC = LoopSetting("realistic", OdomNoise.realistic(), LidarNoise(noise_std=0.01))
# "hard": where loop closure has something to fix. Odometry drifts ~2.5x the realistic profile (5 % scale
# noise, 2 % wheel-radius bias, 0.01 rad/s gyro bias) and SLAM gets a cheap lidar's view: 2.5 cm range
# noise, 3 % dropouts, every 3rd beam (120 of 360).
HARD = LoopSetting("hard", OdomNoise(v_scale_std=0.05, w_scale_std=0.05, v_add_std=0.01, w_add_std=0.02,
                                     scale_bias=0.02, w_bias=0.01),
                   LidarNoise(noise_std=0.025, dropout_prob=0.03), beam_step=3)
SETTINGS = {"realistic": REALISTIC, "hard": HARD}


@dataclass
class DriveResult:
    """How the scripted drive went (ground truth)."""

    waypoints: int
    reached: int  # waypoints reached (== waypoints unless a leg timed out)
    collisions: int  # collision episodes in the sim
    path_length: float  # m driven
    sim_time: float  # s
    max_track_error: float  # m, largest cross-track error while driving a leg

    @property
    def completed(self) -> bool:
        return self.reached == self.waypoints


@dataclass
class SlamLoopResult:
    scene: str
    setting: str
    seed: int
    loop_closure: bool
    ate_rmse: float  # m, SLAM nodes vs ground truth, no alignment (map frame starts at the true start)
    odom_ate_rmse: float  # m, raw odometry at the same stamps: what SLAM had to correct
    iou: float  # occupied-cell IoU, 1-cell tolerance, observed walls only, lidar-plane obstacles
    nodes: int
    scans: int
    loop_closures: int
    slam_seconds: float  # wall s inside SlamEngine.process (informative)
    drive: DriveResult
    optimize_times: list[float] = field(default_factory=list)
    latencies: list[float] = field(default_factory=list)  # wall s of every process() call, in order

    @property
    def scans_per_s(self) -> float:
        return self.scans / self.slam_seconds if self.slam_seconds > 0 else float("nan")


def _wrap(a: float) -> float:
    return math.remainder(a, 2 * math.pi)


class ScriptedDriver:
    """Holonomic P-controller on the true pose: turn in place to the leg heading, then drive the leg at a
    fixed speed with cross-track correction, slowing down over the last ~0.3 m. Deterministic."""

    TURN_TOL = 0.02  # rad: heading reached
    REACH_TOL = 0.015  # m: waypoint reached
    W_MAX = 1.0  # rad/s

    def __init__(self, start: Sequence[float], waypoints: Sequence[Waypoint], speed: float) -> None:
        self.wps = [tuple(map(float, w)) for w in waypoints]
        self.speed = speed
        self.i = 0
        self.seg_start = (float(start[0]), float(start[1]))
        self.turning = True
        self.max_track_error = 0.0

    @property
    def done(self) -> bool:
        return self.i >= len(self.wps)

    def _heading(self) -> float:
        w = self.wps[self.i]
        if len(w) > 2:
            return w[2]
        return math.atan2(w[1] - self.seg_start[1], w[0] - self.seg_start[0])

    def command(self, x: float, y: float, yaw: float) -> tuple[float, float, float]:
        """Body-frame (vx, vy, wz) for the true pose (x, y, yaw)."""
        if self.done:
            return 0.0, 0.0, 0.0
        sx, sy = self.seg_start
        tx, ty = self.wps[self.i][:2]
        e_yaw = _wrap(self._heading() - yaw)
        wz = max(-self.W_MAX, min(self.W_MAX, 2.0 * e_yaw))
        if self.turning:
            vwx, vwy = 1.5 * (sx - x), 1.5 * (sy - y)  # hold position while turning
            if abs(e_yaw) < self.TURN_TOL:
                self.turning = False
        else:
            length = math.hypot(tx - sx, ty - sy)
            dx, dy = (tx - sx) / length, (ty - sy) / length
            along = (x - sx) * dx + (y - sy) * dy
            cx, cy = (x - sx) - along * dx, (y - sy) - along * dy
            self.max_track_error = max(self.max_track_error, math.hypot(cx, cy))
            rem = length - along
            v = max(-self.speed, min(self.speed, 1.2 * rem + math.copysign(0.05, rem)))
            vwx, vwy = v * dx - 2.0 * cx, v * dy - 2.0 * cy
            if abs(rem) < self.REACH_TOL and math.hypot(tx - x, ty - y) < 2 * self.REACH_TOL:
                self.i += 1
                self.seg_start = (tx, ty)
                self.turning = True
        c, s = math.cos(yaw), math.sin(yaw)
        return c * vwx + s * vwy, -s * vwx + c * vwy, wz


@dataclass
class LoopRecording:
    """One scripted drive as SLAM's input: the scans (decimated / range-capped per the setting), the sim's
    drifting odometry and the true pose at each scan, plus the sim's ground-truth grid."""

    scene: str
    setting: str
    seed: int
    scans: list[Scan]
    odom: np.ndarray  # (N, 3) at each scan
    gt: np.ndarray  # (N, 3) at each scan
    drive: DriveResult
    truth: GridMap
    config: SlamConfig  # the SLAM config of the setting


OnScan = Callable[[Scan, tuple[float, float, float], tuple[float, float, float], float], None]


def drive_loop(scene: str, st: LoopSetting, seed: int, wps: list[Waypoint], leg_timeout: float,
               on_scan: OnScan, on_waypoint: Callable[[int, float], None] | None = None,
               lidar: dict[str, float] | None = None) -> tuple[DriveResult, GridMap]:
    """Drive ``wps`` in the sim; ``on_scan(scan, odom, gt, yaw_rate)`` at each 10 Hz lidar scan (the true
    yaw rate, for fault injection that needs to find a fast turn) and, if given, ``on_waypoint(reached,
    driven_m)`` each time a waypoint is reached (so a caller driving a route several times can cut the drive
    into laps). ``lidar`` overrides fields of the robot's LidarSpec (beams, fov, range_max: another
    scanner). Returns how the drive went and the ground-truth grid at the config's resolution. The one sim
    drive loop of the SLAM evaluations and benches."""
    robot = load_robot_description()
    if lidar:
        robot = dataclasses.replace(robot, lidar=dataclasses.replace(robot.lidar, **lidar))
    sim = PandaMobileSim(robot, load_scene(scene), seed=seed, odom_noise=st.odom_noise, lidar_noise=st.lidar_noise)
    cfg = st.slam_config or SlamConfig()
    mx, my, _, myaw = robot.lidar.mount
    mount = (mx, my, myaw)
    x0, y0, _, *_ = sim.ground_truth()
    driver = ScriptedDriver((x0, y0), wps, st.speed)
    ctrl_every = max(1, round(0.05 / sim.timestep))  # 20 Hz control
    scan_every = max(1, round(0.1 / sim.timestep))  # 10 Hz lidar (a multiple of the control period)
    step, leg, leg_t0, driven, last_xy = 0, 0, 0.0, 0.0, (x0, y0)
    while not driver.done:
        sim.step(ctrl_every)
        step += ctrl_every
        x, y, yaw, _, _, wz = sim.ground_truth()
        driven += math.hypot(x - last_xy[0], y - last_xy[1])
        last_xy = (x, y)
        if step % scan_every == 0:
            s, o = sim.scan(), sim.odometry()
            ranges = np.asarray(s.ranges, dtype=np.float32)[::st.beam_step].copy()
            range_max = s.range_max
            if st.max_range is not None:
                range_max = min(range_max, st.max_range)
                ranges[ranges > range_max] = np.inf
            scan = Scan(ranges, s.angle_min, s.angle_increment * st.beam_step, s.range_min, range_max, s.stamp,
                        mount, s.frame_id)
            on_scan(scan, (o.x, o.y, o.yaw), (x, y, yaw), float(wz))
        sim.set_cmd_vel(*driver.command(x, y, yaw), stamp=sim.time)
        if driver.i != leg:  # checked right after the command so the last waypoint is reported too
            leg, leg_t0 = driver.i, sim.time
            if on_waypoint is not None:
                on_waypoint(leg, driven)
        elif sim.time - leg_t0 > leg_timeout:  # stuck (should never happen): give up on the rest
            break
    sim.stop()
    drive = DriveResult(len(wps), driver.i, len(sim.collisions()), driven, sim.time, driver.max_track_error)
    return drive, sim.ground_truth_grid(cfg.resolution, min_height=robot.lidar.mount[2])


def record_loop(scene: str = "apartment", *, seed: int = 0, hard: bool = False,
                route: Sequence[Waypoint] | None = None, setting: LoopSetting | None = None,
                leg_timeout: float = 40.0) -> LoopRecording:
    """Drive the scripted loop once and keep SLAM's input, to feed it later (e.g. paced in wall time
    through the provider's scan path, bench/slam_provider_drops.py)."""
    st = setting or (HARD if hard else REALISTIC)
    scans: list[Scan] = []
    odom: list[tuple[float, float, float]] = []
    gt: list[tuple[float, float, float]] = []

    def keep(scan: Scan, o: tuple[float, float, float], g: tuple[float, float, float], _wz: float) -> None:
        scans.append(scan)
        odom.append(o)
        gt.append(g)

    drive, truth = drive_loop(scene, st, seed, list(route or LOOPS[scene]), leg_timeout, keep)
    return LoopRecording(scene, st.name, seed, scans, np.asarray(odom, dtype=float).reshape(-1, 3),
                         np.asarray(gt, dtype=float).reshape(-1, 3), drive, truth, st.slam_config or SlamConfig())


def run_slam_loops(scene: str = "apartment", *, seed: int = 0, hard: bool = False,
                   route: Sequence[Waypoint] | None = None, setting: LoopSetting | None = None,
                   leg_timeout: float = 40.0) -> tuple[SlamLoopResult, SlamLoopResult]:
    """(LC on, LC off) from ONE scripted drive of ``route`` (default LOOPS[scene]) under ``setting``
    (default HARD if ``hard`` else REALISTIC): both engines get identical scans and odometry."""
    st = setting or (HARD if hard else REALISTIC)
    cfg = st.slam_config or SlamConfig()
    engines = {lc: SlamEngine(SlamConfig.from_dict({**cfg.to_dict(), "loop_closure": lc})) for lc in (True, False)}
    seconds = {True: 0.0, False: 0.0}
    latencies: dict[bool, list[float]] = {True: [], False: []}
    gt_at: dict[float, tuple[float, float, float]] = {}
    odom_at: dict[float, tuple[float, float, float]] = {}
    wps = list(route or LOOPS[scene])

    def feed(scan: Scan, o: tuple[float, float, float], g: tuple[float, float, float], _wz: float) -> None:
        t = round(scan.stamp, 6)
        gt_at[t], odom_at[t] = g, o
        for lc, eng in engines.items():
            t0 = time.perf_counter()
            eng.process(scan, o, scan.stamp)
            latencies[lc].append(time.perf_counter() - t0)
            seconds[lc] += latencies[lc][-1]

    drive, truth = drive_loop(scene, st, seed, wps, leg_timeout, feed)
    out = []
    for lc, eng in engines.items():
        eng.flush()  # the map may lag the optimised poses by a few calls' re-render budget: score the final map
        stamps = [round(float(t), 6) for t in eng.node_stamps()]
        gt = np.array([gt_at[t] for t in stamps]).reshape(-1, 3)
        odom = np.array([odom_at[t] for t in stamps]).reshape(-1, 3)
        est = eng.trajectory()
        out.append(SlamLoopResult(
            scene=scene, setting=st.name, seed=seed, loop_closure=lc, ate_rmse=ate_rmse(est, gt),
            odom_ate_rmse=ate_rmse(odom, gt),
            iou=occupied_iou(eng.map(), truth, tolerance_cells=1, observed_only=True), nodes=len(est),
            scans=eng.stats.scans_received, loop_closures=eng.stats.loop_closures, slam_seconds=seconds[lc],
            drive=drive, optimize_times=list(eng.optimize_times), latencies=latencies[lc]))
    return out[0], out[1]


def run_slam_loop(scene: str = "apartment", *, loop_closure: bool = True, seed: int = 0,
                  route: Sequence[Waypoint] | None = None, setting: LoopSetting | None = None,
                  hard: bool = False) -> SlamLoopResult:
    """Drive the scripted loop and score SLAM against ground truth, with loop closure on or off."""
    on, off = run_slam_loops(scene, seed=seed, hard=hard, route=route, setting=setting)
    return on if loop_closure else off
