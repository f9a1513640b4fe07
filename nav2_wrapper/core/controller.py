"""Local controller for a holonomic base: regulated pure pursuit in (vx, vy) with heading alignment in wz,
plus a small fallback sampler checked against the footprint on the local costmap.

Why pursuit + fallbacks rather than a full DWB/MPPI sampler: a holonomic base can translate toward the
carrot directly, so the only choices that matter are how fast and whether rotating is safe right now; a
handful of candidates covers them in well under a millisecond.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_api.geometry import wrap_angle

from .costmap import Costmap
from .costs import LETHAL, NO_INFORMATION, distance_from_cost
from .footprint import Footprint


@dataclass
class ControllerConfig:
    max_vel_x: float = 0.5
    max_vel_y: float = 0.5
    max_vel_theta: float = 1.9
    acc_lim_x: float = 1.5
    acc_lim_y: float = 1.5
    acc_lim_theta: float = 3.0
    desired_linear_vel: float = 0.5
    lookahead_dist: float = 0.6
    min_lookahead_dist: float = 0.3
    max_lookahead_dist: float = 0.9
    lookahead_time: float = 1.5
    use_velocity_scaled_lookahead_dist: bool = True
    approach_velocity_scaling_dist: float = 0.6
    min_approach_linear_velocity: float = 0.05
    use_cost_regulated_linear_velocity_scaling: bool = True
    cost_scaling_dist: float = 0.6
    cost_scaling_gain: float = 1.0
    regulated_linear_scaling_min_speed: float = 0.15
    rotation_gain: float = 2.5                 # wz = gain · yaw error (clamped)
    allow_reversed_heading: bool = True        # front/back-symmetric footprint: align either end with the path
    rotate_to_goal_dist: float = 0.5           # m: within this of the goal, turn toward the goal yaw
    collision_check_time: float = 1.0          # s of forward simulation per candidate
    sim_dt: float = 0.1
    footprint: Footprint = field(default_factory=Footprint.from_robot_yaml)


@dataclass
class ControlOutput:
    vx: float
    vy: float
    wz: float
    blocked: bool = False          # no collision-free command except stopping
    remaining: float = 0.0         # m along the path to its end
    detail: str = ""


class HolonomicController:
    def __init__(self, cfg: ControllerConfig | None = None) -> None:
        self.cfg = cfg or ControllerConfig()
        self.speed_limit = 1.0     # fraction of the max velocities (Nav2 speed limit as a percentage / 100)
        self._points = self.cfg.footprint.outline_points(0.025)
        self.set_path(np.zeros((0, 2)))

    def set_speed_limit(self, limit: float, percentage: bool = True) -> None:
        """Nav2 SpeedLimit: a percentage (0 < p ≤ 100; 0 means no limit) or an absolute m/s cap."""
        if limit <= 0:
            self.speed_limit = 1.0
        elif percentage:
            self.speed_limit = min(limit, 100.0) / 100.0
        else:
            self.speed_limit = min(1.0, limit / max(self.cfg.max_vel_x, self.cfg.max_vel_y))

    def set_path(self, path: NDArray[np.float64]) -> None:
        self.path = np.asarray(path, dtype=float).reshape(-1, 2)
        seg = np.hypot(*np.diff(self.path, axis=0).T) if len(self.path) > 1 else np.zeros(0)
        self._cum = np.concatenate([[0.0], np.cumsum(seg)])
        self._idx = -1

    def _closest(self, x: float, y: float) -> int:
        """Nearest path index, searched forward from the last one (so loops in the path don't confuse it)."""
        if self._idx < 0:
            lo, hi = 0, len(self.path)
        else:
            lo = self._idx
            hi = int(np.searchsorted(self._cum, self._cum[lo] + 2.0)) + 1
        d = np.hypot(self.path[lo:hi, 0] - x, self.path[lo:hi, 1] - y)
        self._idx = lo + int(np.argmin(d))
        return self._idx

    def remaining(self, pose: tuple[float, float, float]) -> float:
        if len(self.path) == 0:
            return 0.0
        i = self._closest(pose[0], pose[1])
        return float(self._cum[-1] - self._cum[i] + math.hypot(self.path[i, 0] - pose[0], self.path[i, 1] - pose[1]))

    def compute(self, pose: tuple[float, float, float], vel: tuple[float, float, float],
                goal: tuple[float, float, float], costmap: Costmap, dt: float, xy_reached: bool = False) -> ControlOutput:
        """One control step: pose in the costmap frame, vel = measured body (vx, vy, wz), dt since last step."""
        c = self.cfg
        x, y, th = (float(v) for v in pose)
        if len(self.path) == 0:
            return ControlOutput(0.0, 0.0, 0.0, True, 0.0, "no path")
        i = self._closest(x, y)
        remaining = self.remaining(pose)
        speed_now = math.hypot(vel[0], vel[1])
        la = (min(max(speed_now * c.lookahead_time, c.min_lookahead_dist), c.max_lookahead_dist)
              if c.use_velocity_scaled_lookahead_dist else c.lookahead_dist)
        d_ahead = np.hypot(self.path[i:, 0] - x, self.path[i:, 1] - y)
        far = np.flatnonzero(d_ahead >= la)
        carrot = self.path[i + int(far[0])] if len(far) else self.path[-1]
        dgoal = math.hypot(goal[0] - x, goal[1] - y)
        to_end = not len(far)
        # --- heading target
        if xy_reached or dgoal < c.rotate_to_goal_dist:
            yaw_target = goal[2]
        else:
            j = min(i + int(far[0]) if len(far) else len(self.path) - 1, len(self.path) - 1)
            k = max(j - 3, 0)
            seg = self.path[j] - self.path[k]
            yaw_target = math.atan2(seg[1], seg[0]) if np.hypot(*seg) > 1e-6 else th
        err = float(wrap_angle(yaw_target - th))
        if c.allow_reversed_heading and not (xy_reached or dgoal < c.rotate_to_goal_dist) and abs(err) > math.pi / 2:
            err = float(wrap_angle(err + math.pi))
        wz = float(np.clip(c.rotation_gain * err, -c.max_vel_theta, c.max_vel_theta)) * self.speed_limit
        # --- translational speed
        v = c.desired_linear_vel * self.speed_limit
        if remaining < c.approach_velocity_scaling_dist:
            v = max(v * remaining / c.approach_velocity_scaling_dist, min(c.min_approach_linear_velocity, v))
        if c.use_cost_regulated_linear_velocity_scaling:
            centre = int(costmap.cost_at(x, y, outside=0))
            if centre != NO_INFORMATION:
                dobs = distance_from_cost(centre, costmap.cfg.footprint.inscribed_radius, costmap.cfg.cost_scaling_factor)
                if dobs < c.cost_scaling_dist:
                    v = max(v * c.cost_scaling_gain * dobs / c.cost_scaling_dist,
                            min(c.regulated_linear_scaling_min_speed, v))
        v *= max(0.3, math.cos(min(abs(err), math.pi / 2)))
        aim = np.array([carrot[0] - x, carrot[1] - y])
        if to_end or xy_reached:
            aim = np.array([goal[0] - x, goal[1] - y])
            v = min(v, 1.5 * float(np.hypot(*aim)))
        if xy_reached:
            v = min(v, 0.5 * float(np.hypot(*aim)))
        n = float(np.hypot(*aim))
        vm = aim / n * v if n > 1e-9 else np.zeros(2)
        cs, sn = math.cos(th), math.sin(th)
        vx, vy = cs * vm[0] + sn * vm[1], -sn * vm[0] + cs * vm[1]
        lim = max(abs(vx) / (c.max_vel_x * self.speed_limit), abs(vy) / (c.max_vel_y * self.speed_limit), 1.0)
        vx, vy = vx / lim, vy / lim
        vx, vy, wz = self._accel_limit((vx, vy, wz), vel, dt)
        cmd, blocked = self._collision_free((vx, vy, wz), pose, costmap)
        return ControlOutput(*cmd, blocked, remaining, "")

    def _accel_limit(self, cmd: tuple[float, float, float], vel: tuple[float, float, float],
                     dt: float) -> tuple[float, float, float]:
        c = self.cfg
        dt = max(dt, 1e-3)
        out = []
        for u, v0, a in zip(cmd, vel, (c.acc_lim_x, c.acc_lim_y, c.acc_lim_theta), strict=True):
            out.append(float(np.clip(u, v0 - a * dt, v0 + a * dt)))
        return out[0], out[1], out[2]

    def _collision_free(self, cmd: tuple[float, float, float], pose: tuple[float, float, float],
                        costmap: Costmap) -> tuple[tuple[float, float, float], bool]:
        """First candidate whose simulated footprint never touches more lethal cells than it touches now."""
        vx, vy, wz = cmd
        cands = [(vx, vy, wz), (vx, vy, 0.0), (0.5 * vx, 0.5 * vy, wz), (0.5 * vx, 0.5 * vy, 0.0),
                 (0.25 * vx, 0.25 * vy, 0.0), (0.0, 0.0, wz)]
        cands = [cd for cd in cands if any(abs(u) > 1e-6 for u in cd)]
        if not cands:
            return (0.0, 0.0, 0.0), False
        hits = self.trajectory_hits(np.array(cands), pose, costmap)
        for cd, h in zip(cands, hits, strict=True):
            if not h:
                return cd, False
        return (0.0, 0.0, 0.0), True

    def trajectory_hits(self, cands: NDArray[np.float64], pose: tuple[float, float, float],
                        costmap: Costmap, horizon: float | None = None) -> NDArray[np.bool_]:
        """For body-velocity candidates (K, 3), whether the forward-simulated footprint hits a lethal cell
        it is not already touching at the start."""
        c = self.cfg
        horizon = c.collision_check_time if horizon is None else horizon
        steps = max(1, int(math.ceil(horizon / c.sim_dt)))
        t = np.arange(1, steps + 1) * c.sim_dt
        th = pose[2] + cands[:, 2:3] * t[None, :]                        # (K, T)
        # exact integration of constant body twist, done by small steps for simplicity
        cth = np.cos(pose[2] + cands[:, 2:3] * (t[None, :] - c.sim_dt / 2))
        sth = np.sin(pose[2] + cands[:, 2:3] * (t[None, :] - c.sim_dt / 2))
        dx = (cth * cands[:, 0:1] - sth * cands[:, 1:2]) * c.sim_dt
        dy = (sth * cands[:, 0:1] + cth * cands[:, 1:2]) * c.sim_dt
        poses = np.stack([pose[0] + np.cumsum(dx, axis=1), pose[1] + np.cumsum(dy, axis=1), th], axis=-1)
        now = int(np.sum(costmap.footprint_costs(np.array(pose), self._points, outside=0) == LETHAL))
        fc = costmap.footprint_costs(poses.reshape(-1, 3), self._points, outside=0) == LETHAL
        per_pose = fc.sum(axis=1).reshape(len(cands), steps)
        return np.any(per_pose > now, axis=1)
