"""PandaMobileSim: the simulation core a thin provider wraps (no DDS, gRPC or atlas in here).

Stepping runs as many MuJoCo steps per Python call as the next event allows (odometry tick, contact
check, cmd_vel deadline), so Python overhead is paid per event, not per 2 ms physics step.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from robonix_common.grid import GridMap

from .errors import SimConfigError
from .lidar import Lidar, ScanResult
from .mjcf import BASE_BODY, LIDAR_SITE, OBSTACLE_PREFIX, build_mjcf, yaw_of
from .odometry import Odometry, OdomNoise, OdomState, compose, relative
from .raster import rasterize
from .robot import RobotDescription
from .scene import Obstacle, Scene, check_start, first_collision
from .shapes import Rect
from .spec import check_ranges, param

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LidarNoise:
    """Range noise of the simulated lidar, when a run overrides the robot description's."""

    noise_std: float = param(0.0, ge=0, doc="m, Gaussian on valid returns")
    dropout_prob: float = param(0.0, ge=0, le=1, doc="per beam, reported as +inf")

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class SimParams:
    """Everything about a run that is not robot or scene; checked so errors name the field."""

    seed: int = param(0, ge=0, le=2**63 - 1, doc="seeds odometry and lidar noise; same seed, same run")
    timestep: float = param(0.002, gt=0, le=0.002, doc="s, physics step (>= 500 Hz)")
    odom_rate_hz: float = param(50.0, gt=0, le=1000.0, doc="sim-time Hz of odometry integration")
    contact_check_interval: float = param(0.01, gt=0, doc="s between contact scans (>= one step)")
    collision_debounce: float = param(0.2, ge=0, doc="s without contact that ends a collision episode")
    odom_noise: OdomNoise = field(default_factory=OdomNoise)
    lidar_noise: LidarNoise | None = None  # None: the robot description's noise_std/dropout_prob
    odom_frame_at_start: bool = param(False, doc="true: odom starts at (0, 0, 0); false: odom frame == world")

    def __post_init__(self) -> None:
        check_ranges(self)
        if not isinstance(self.odom_noise, OdomNoise):
            raise SimConfigError(f"odom_noise: expected an OdomNoise, got {type(self.odom_noise).__name__}")
        if self.lidar_noise is not None and not isinstance(self.lidar_noise, LidarNoise):
            raise SimConfigError(f"lidar_noise: expected a LidarNoise or None, got {type(self.lidar_noise).__name__}")


@dataclass(frozen=True)
class CollisionEvent:
    time: float
    robot_geom: str
    other_geom: str  # obstacle name (scene or spawned)
    x: float  # contact point, world frame
    y: float


@dataclass(frozen=True)
class CmdStatus:
    """What set_cmd_vel applied, and whether it had to change the request."""

    vx: float
    vy: float
    wz: float
    clamped: bool
    nonplanar_ignored: bool
    rejected: bool = False


class PandaMobileSim:
    def __init__(self, robot: RobotDescription, scene: Scene, seed: int = 0, odom_noise: OdomNoise | None = None,
                 lidar_noise: LidarNoise | None = None, **params: Any) -> None:
        names = {f.name for f in dataclasses.fields(SimParams)}
        unknown = sorted(set(params) - names)
        if unknown:
            raise SimConfigError(f"sim: {unknown[0]}: unknown parameter (known: {', '.join(sorted(names))})")
        try:
            self.params = SimParams(seed=seed, odom_noise=odom_noise or OdomNoise(), lidar_noise=lidar_noise,
                                    **params)
        except SimConfigError as exc:
            raise SimConfigError(f"sim: {exc}") from None
        check_start(scene, robot)
        self.robot, self.scene = robot, scene
        self.warnings: list[str] = []
        self._warned: set[str] = set()
        self._spawned: list[Obstacle] = []
        dt = self.params.timestep
        self._odom_every = max(1, round(1.0 / (self.params.odom_rate_hz * dt)))
        self._contact_every = max(1, round(self.params.contact_check_interval / dt))
        self._debounce_steps = round(self.params.collision_debounce / dt)
        self._compile()
        self.reset()

    # ----------------------------------------------------------------- model
    def _compile(self) -> None:
        obstacles = self.scene.obstacles() + self._spawned
        xml = build_mjcf(self.robot, obstacles, self.scene.bounds, self.params.timestep)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, BASE_BODY)
        self._site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, LIDAR_SITE)
        self._robot_geoms = {int(g) for g in np.flatnonzero(m.geom_bodyid == self._base)}
        self._geom_names = {g: (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}")
                            .removeprefix(OBSTACLE_PREFIX) for g in range(m.ngeom)}

    def _make_rngs(self) -> None:
        odom_ss, lidar_ss = np.random.SeedSequence(self.params.seed).spawn(2)
        self._odom_rng, self._lidar_rng = np.random.default_rng(odom_ss), np.random.default_rng(lidar_ss)

    def _make_lidar(self) -> None:
        ln = self.params.lidar_noise or LidarNoise(noise_std=self.robot.lidar.noise_std,
                                                   dropout_prob=self.robot.lidar.dropout_prob)
        self._lidar = Lidar(self.model, self.robot.lidar, self._site, self._base, self._lidar_rng,
                            ln.noise_std, ln.dropout_prob)

    # ----------------------------------------------------------------- state
    @property
    def time(self) -> float:
        """Sim seconds since reset (exact multiple of the timestep)."""
        return self._steps * self.params.timestep

    @property
    def timestep(self) -> float:
        return self.params.timestep

    def reset(self, keep_spawned: bool = False) -> None:
        """Back to the scene's start pose at t = 0 with fresh RNGs: a reset run replays identically."""
        if self._spawned and not keep_spawned:
            self._spawned = []
            self._compile()
        mujoco.mj_resetData(self.model, self.data)
        self._make_rngs()
        self._make_lidar()
        self._steps = 0
        self._next_odom, self._next_contact = self._odom_every, self._contact_every
        self._deadline: int | None = None
        self._events: list[CollisionEvent] = []
        self._active: dict[tuple[str, str], int] = {}  # by name: survives the recompile of spawn_box
        start = self.scene.start
        self.data.qpos[:3] = start
        mujoco.mj_forward(self.model, self.data)
        self._dirty = False
        self._odom = Odometry(self.params.odom_noise, self._odom_rng)
        origin = (0.0, 0.0, 0.0) if self.params.odom_frame_at_start else start
        self._odom.reset(origin, start, 0.0)

    def _kin(self) -> None:
        if self._dirty:
            mujoco.mj_kinematics(self.model, self.data)
            self._dirty = False

    def _pose(self) -> tuple[float, float, float]:
        self._kin()
        p, r = self.data.xpos[self._base], self.data.xmat[self._base]
        return float(p[0]), float(p[1]), yaw_of(r)

    def ground_truth(self) -> tuple[float, float, float, float, float, float]:
        """(x, y, yaw) in the world, (vx, vy, wz) in the body frame."""
        x, y, yaw = self._pose()
        vx, vy, wz = self.data.qvel[:3]
        c, s = math.cos(yaw), math.sin(yaw)
        return x, y, yaw, float(c * vx + s * vy), float(-s * vx + c * vy), float(wz)

    def odometry(self) -> OdomState:
        gt = self.ground_truth()
        return self._odom.state(gt[:3], gt[3:], self.time)

    # ----------------------------------------------------------------- crash continuity
    def resume_state(self) -> dict[str, Any]:
        """What a restarted simulator needs to go on where this one stopped: sim time (steps), the base's
        true pose and the odometry's integrated pose (see ``hal_panda_mobile.persist``)."""
        return {"steps": int(self._steps), "timestep": self.params.timestep, "true": list(self._pose()),
                "odom": list(self._odom.pose), "odom_last_true": list(self._odom.last_true)}

    def restore(self, state: dict[str, Any], min_time: float = 0.0) -> None:
        """Continue a saved run: the base at rest at its saved true pose, odometry where it was (its pose
        extended by the truth's motion since its last tick, so odom→base stays consistent with the truth) and
        sim time at the saved time or ``min_time``, whichever is later (never behind a clock already seen).
        SimConfigError when the state does not fit this simulator (timestep, a non-finite pose)."""
        if abs(float(state["timestep"]) - self.params.timestep) > 1e-12:
            raise SimConfigError(f"resume: timestep {state['timestep']} differs from {self.params.timestep}")
        x, y, yaw = (float(v) for v in state["true"])
        odom = compose(tuple(map(float, state["odom"])),  # type: ignore[arg-type]
                       relative(tuple(map(float, state["odom_last_true"])), (x, y, yaw)))  # type: ignore[arg-type]
        steps = max(int(state["steps"]), math.ceil(min_time / self.params.timestep - 1e-9))
        if not all(math.isfinite(v) for v in (x, y, yaw, *odom)):
            raise SimConfigError("resume: saved pose is not finite")
        self.stop()
        self.data.qpos[:3] = (x, y, yaw)  # no collision check: the base was there (possibly touching a wall)
        self.data.qvel[:3] = 0.0
        mujoco.mj_forward(self.model, self.data)
        self._dirty = False
        self._active.clear()
        self._steps = steps
        self._next_odom = steps + self._odom_every
        self._next_contact = steps + self._contact_every
        self.data.time = self.time
        self._odom.reset(odom, (x, y, yaw), self.time)

    # ----------------------------------------------------------------- command
    def _warn_once(self, key: str, msg: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            self.warnings.append(msg)
            log.warning(msg)

    def set_cmd_vel(self, vx: float, vy: float, wz: float, stamp: float | None = None, *,
                    vz: float = 0.0, wx: float = 0.0, wy: float = 0.0) -> CmdStatus:
        """Body-frame twist, clamped to the limits; held until ``stamp + cmd_vel_timeout`` (sim time)."""
        nonplanar = any(v != 0.0 for v in (vz, wx, wy))
        if nonplanar:
            self._warn_once("nonplanar", "cmd_vel: linear.z, angular.x and angular.y are ignored (planar base)")
        if not all(math.isfinite(v) for v in (vx, vy, wz)):
            self._warn_once("nonfinite", "cmd_vel: non-finite component received; stopping instead")
            self.stop()
            return CmdStatus(0.0, 0.0, 0.0, False, nonplanar, rejected=True)
        lim = self.robot.limits
        req = (vx, vy, wz)
        cmd = (min(max(vx, -lim.max_vx), lim.max_vx), min(max(vy, -lim.max_vy), lim.max_vy),
               min(max(wz, -lim.max_wz), lim.max_wz))
        stamp = self.time if stamp is None else stamp
        deadline = math.ceil((stamp + self.robot.cmd_vel_timeout) / self.params.timestep - 1e-9)
        if deadline <= self._steps:
            self.stop()
            return CmdStatus(0.0, 0.0, 0.0, False, nonplanar, rejected=True)
        self.data.ctrl[:3] = cmd
        self._deadline = deadline
        return CmdStatus(*cmd, clamped=cmd != req, nonplanar_ignored=nonplanar)

    @property
    def commanding(self) -> bool:
        """True while a non-zero command is being held (before its timeout)."""
        return self._deadline is not None and bool(np.any(self.data.ctrl[:3] != 0.0))

    def stop(self) -> None:
        """Zero target: the base decelerates at its limits and holds."""
        self.data.ctrl[:3] = 0.0
        self._deadline = None

    # ----------------------------------------------------------------- stepping
    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps."""
        m, d = self.model, self.data
        while n > 0:
            k = min(n, self._next_odom - self._steps, self._next_contact - self._steps)
            if self._deadline is not None:
                k = min(k, self._deadline - self._steps)
            mujoco.mj_step(m, d, k)
            self._steps += k
            n -= k
            self._dirty = True
            if self._deadline is not None and self._steps >= self._deadline:
                self.stop()
            if self._steps >= self._next_contact:
                self._next_contact += self._contact_every
                if d.ncon or self._active:
                    self._check_contacts()
            if self._steps >= self._next_odom:
                self._next_odom += self._odom_every
                self._odom.tick(self._pose(), self.time)
        d.time = self.time

    def step_for(self, seconds: float) -> None:
        self.step(max(0, round(seconds / self.params.timestep)))

    def _check_contacts(self) -> None:
        d, now = self.data, self._steps
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            if g1 in self._robot_geoms:
                rg, og = g1, g2
            elif g2 in self._robot_geoms:
                rg, og = g2, g1
            else:
                continue
            if og in self._robot_geoms:
                continue
            key = (self._geom_names[rg], self._geom_names[og])
            if key not in self._active:
                self._events.append(CollisionEvent(self.time, *key, float(c.pos[0]), float(c.pos[1])))
            self._active[key] = now
        for key, seen in list(self._active.items()):
            if now - seen > self._debounce_steps:
                del self._active[key]

    def collisions(self, since: float | None = None) -> list[CollisionEvent]:
        """Collision episodes (first contact of each), oldest first; ``since`` is exclusive."""
        return [e for e in self._events if since is None or e.time > since]

    # ----------------------------------------------------------------- sensors
    def scan(self) -> ScanResult:
        self._kin()
        return self._lidar.scan(self.data, self.time)

    # ----------------------------------------------------------------- world edits
    def _all_obstacles(self) -> list[Obstacle]:
        return self.scene.obstacles() + self._spawned

    def teleport(self, x: float, y: float, yaw: float, reset_odom: bool = True) -> None:
        """Place the base at rest; rejects a pose in collision. Without ``reset_odom`` odometry keeps
        its estimate and never integrates the jump (a kidnapped robot)."""
        if not all(math.isfinite(v) for v in (x, y, yaw)):
            raise SimConfigError(f"teleport: pose ({x}, {y}, {yaw}) is not finite")
        ob = first_collision(self.robot, self._all_obstacles(), x, y, yaw)
        if ob is not None:
            raise SimConfigError(f"teleport: pose ({x:g}, {y:g}, {yaw:g}) collides with {ob.ref} {ob.name!r}")
        self.stop()
        self.data.qpos[:3] = (x, y, yaw)
        self.data.qvel[:3] = 0.0
        mujoco.mj_forward(self.model, self.data)
        self._dirty = False
        self._active.clear()
        if reset_odom:
            origin = (0.0, 0.0, 0.0) if self.params.odom_frame_at_start else (x, y, yaw)
            self._odom.reset(origin, (x, y, yaw), self.time)
        else:
            self._odom.rebase((x, y, yaw), self.time)

    def spawn_box(self, name: str, x: float, y: float, sx: float, sy: float, yaw: float = 0.0,
                  height: float = 0.8) -> None:
        """Add a static box (full sizes sx, sy) by recompiling the model and carrying the state over."""
        vals = {"x": x, "y": y, "sx": sx, "sy": sy, "yaw": yaw, "height": height}
        for key, v in vals.items():
            if not math.isfinite(v) or (key in ("sx", "sy", "height") and v <= 0):
                need = " > 0" if key in ("sx", "sy", "height") else ""
                raise SimConfigError(f"spawn_box: {key}: must be a finite number{need}, got {v}")
        if not name or any(ob.name == name for ob in self._all_obstacles()):
            raise SimConfigError(f"spawn_box: name: {name!r} is empty or already used")
        ob = Obstacle(name, f"spawned[{len(self._spawned)}]", Rect(x, y, sx, sy, yaw), height)
        if first_collision(self.robot, [ob], *self._pose()) is not None:
            raise SimConfigError(f"spawn_box: box {name!r} would overlap the robot")
        self._recompile_with(self._spawned + [ob])

    def remove_box(self, name: str) -> None:
        if not any(ob.name == name for ob in self._spawned):
            raise SimConfigError(f"remove_box: name: no spawned box {name!r}")
        self._recompile_with([ob for ob in self._spawned if ob.name != name])

    def _recompile_with(self, spawned: list[Obstacle]) -> None:
        old = self.data
        qpos, qvel, ctrl, act = old.qpos.copy(), old.qvel.copy(), old.ctrl.copy(), old.act.copy()
        self._spawned = spawned
        self._compile()
        d = self.data
        d.qpos[:], d.qvel[:], d.ctrl[:], d.act[:] = qpos, qvel, ctrl, act
        d.time = self.time
        mujoco.mj_forward(self.model, d)
        self._dirty = False
        self._lidar = Lidar(self.model, self.robot.lidar, self._site, self._base, self._lidar_rng,
                            self._lidar.noise_std, self._lidar.dropout_prob)

    # ----------------------------------------------------------------- scene views
    def scene_info(self) -> dict[str, Any]:
        def desc(ob: Obstacle) -> dict[str, Any]:
            s = ob.shape
            shape = ({"type": "box", "center": [s.cx, s.cy], "size": [s.sx, s.sy], "yaw": s.yaw}
                     if isinstance(s, Rect) else {"type": "cylinder", "center": [s.cx, s.cy], "radius": s.r})
            return {"name": ob.name, "ref": ob.ref, "height": ob.height, **shape}

        return {"name": self.scene.name, "description": self.scene.description,
                "bounds": list(self.scene.bounds), "start": list(self.scene.start),
                "waypoints": {k: list(v) for k, v in self.scene.waypoints.items()},
                "obstacles": [desc(ob) for ob in self._all_obstacles()]}

    def ground_truth_grid(self, resolution: float = 0.05, *, min_height: float = 0.0, inflate: float = 0.0,
                          overlap: bool = True) -> GridMap:
        """The scene's obstacles (incl. spawned boxes) rasterised over its bounds, for scoring maps."""
        return rasterize(self._all_obstacles(), self.scene.bounds, resolution, inflate=inflate,
                         min_height=min_height, overlap=overlap)
