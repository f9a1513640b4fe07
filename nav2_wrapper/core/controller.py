"""Local controller for a holonomic base: regulated pure pursuit in (vx, vy) with heading alignment in wz,
plus a small fallback sampler checked against the footprint on the local costmap.

Heading: in open space the body turns toward the path direction at the carrot; in a narrow passage ahead it
lines up with the passage instead (the yaw that fits the footprint best at the tightest path point), since a
0.7 × 0.5 m body held diagonally needs ~0.8 m. Candidates are simulated as the pursuit executes them (fixed
world-frame translation, rotation that stops at its target), and lethal cells the outline already touches are
forgiven rather than counted, so a noise speckle on the outline cannot veto every command.

Why pursuit + fallbacks rather than a full DWB/MPPI sampler: a holonomic base can translate toward the
carrot directly, so the only choices that matter are how fast and whether rotating is safe right now; a
handful of candidates covers them in well under a millisecond.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import Pose2D, wrap_angle
from robonix_common.params import param

from .costmap import Costmap
from .costs import LETHAL, NO_INFORMATION, distance_from_cost
from .footprint import Footprint
from .latency import mean_twist, predict_pose


@dataclass
class ControllerConfig:
    """The controller plugin's parameters (``controller_server.<controller>``); the footprint comes from the
    robot description and is passed in, never read here."""

    footprint: Footprint = field(kw_only=True)
    max_vel_x: float = param(0.5, "body-frame speed limit along x", unit="m/s", gt=0)
    max_vel_y: float = param(0.5, "body-frame speed limit along y (0: no sideways motion)", unit="m/s", ge=0)
    max_vel_theta: float = param(1.9, "turn rate limit", unit="rad/s", gt=0)
    acc_lim_x: float = param(1.5, "acceleration limit along x", unit="m/s^2", gt=0)
    acc_lim_y: float = param(1.5, "acceleration limit along y", unit="m/s^2", gt=0)
    acc_lim_theta: float = param(3.0, "angular acceleration limit (also caps turns so they can brake in time)",
                                 unit="rad/s^2", gt=0)
    desired_linear_vel: float = param(0.5, "cruise speed before regulation and the speed limit", unit="m/s", gt=0)
    lookahead_dist: float = param(0.6, "carrot distance when use_velocity_scaled_lookahead_dist is false",
                                  unit="m", gt=0)
    min_lookahead_dist: float = param(0.3, "lower bound of the velocity-scaled carrot distance", unit="m", gt=0)
    max_lookahead_dist: float = param(0.9, "upper bound of the velocity-scaled carrot distance", unit="m", gt=0)
    lookahead_time: float = param(1.5, "velocity-scaled carrot distance = speed * this", unit="s", gt=0)
    use_velocity_scaled_lookahead_dist: bool = param(True, "scale the carrot distance with the measured speed")
    approach_velocity_scaling_dist: float = param(0.6, "slow down linearly within this distance of the path end",
                                                  unit="m", gt=0)
    min_approach_linear_velocity: float = param(0.05, "the approach slow-down does not go below this", unit="m/s",
                                                ge=0)
    use_cost_regulated_linear_velocity_scaling: bool = param(True, "slow down near obstacles (inflated cost)")
    cost_scaling_dist: float = param(0.6, "slow down when the nearest obstacle is closer than this", unit="m", gt=0)
    cost_scaling_gain: float = param(1.0, "speed factor = gain * obstacle distance / cost_scaling_dist", gt=0)
    regulated_linear_scaling_min_speed: float = param(0.15, "the cost regulation does not go below this",
                                                      unit="m/s", ge=0)
    rotation_gain: float = param(2.5, "wz = gain * heading error (clamped)", unit="1/s", gt=0)
    allow_reversed_heading: bool = param(
        True, "front/back-symmetric footprint: either end may lead along the path")
    rotate_to_goal_dist: float = param(0.5, "within this of the goal, turn toward the goal yaw", unit="m", ge=0)
    collision_check_time: float = param(1.0, "forward simulation of each candidate command", unit="s", gt=0)
    tight_clearance: float = param(
        0.15, "obstacles closer than circumscribed radius + this make a narrow passage", unit="m", ge=0)
    dense_time: float = param(0.25, "the first part of the simulation, sampled finely (runs before the next check)",
                              unit="s", gt=0)
    footprint_check_resolution: float = param(
        0.05, "dense sampling keeps outline points within half this apart (the costmap cell size)", unit="m", gt=0)
    passage_lookahead: float = param(1.0, "path searched for a narrow passage to line the body up with", unit="m",
                                     ge=0)
    sim_dt: float = param(0.1, "coarse step of the forward simulation", unit="s", gt=0)
    latency_compensation: bool = param(
        True, "plan each command from where the base will be when it takes effect (the measured control latency "
        "ahead of the pose, at the measured twist); no effect where the simulator waits for the controller")
    max_latency: float = param(0.5, "latency predicted over at most (a larger measured one is capped here)",
                               unit="s", ge=0, le=2.0)
    max_blind_travel: float = param(
        0.15, "distance the base may cover during one measured latency: above it the speed is cut to this / latency "
        "(a starved machine then drives slower instead of blind), not below regulated_linear_scaling_min_speed",
        unit="m", gt=0)


@dataclass
class ControlOutput:
    vx: float
    vy: float
    wz: float
    blocked: bool = False          # no collision-free command except stopping
    remaining: float = 0.0         # m along the path to its end
    detail: str = ""


class HolonomicController:
    def __init__(self, cfg: ControllerConfig) -> None:
        self.cfg = cfg
        self.speed_limit = 1.0     # fraction of the max velocities (Nav2 speed limit as a percentage / 100)
        self.latency = 0.0         # s from the pose's stamp until a command takes effect (set by the process loop)
        self.measured_latency = 0.0   # the same before the max_latency cap
        self.last_sent: tuple[float, float, float] | None = None   # the command the base is executing meanwhile
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

    def set_latency(self, seconds: float, last_sent: tuple[float, float, float] | None = None) -> None:
        """The control latency measured by the process running this controller (0: commands act at once) and
        the last command it sent (what the base executes until this step's command arrives; None: unknown,
        then the measured twist is assumed to hold)."""
        self.measured_latency = max(float(seconds), 0.0) if math.isfinite(seconds) else 0.0
        self.latency = min(self.measured_latency, self.cfg.max_latency)
        self.last_sent = last_sent

    def latency_speed_fraction(self) -> float:
        """The speed-limit fraction that keeps speed × measured latency within ``max_blind_travel`` (1: no cut),
        but never below ``regulated_linear_scaling_min_speed``: the cut multiplies with the approach and
        obstacle slow-downs, and a base crawling below that floor fails the progress check instead."""
        c = self.cfg
        if not c.latency_compensation or self.measured_latency <= 0.0:
            return 1.0
        vmax = max(c.max_vel_x, c.max_vel_y)
        floor = min(1.0, c.regulated_linear_scaling_min_speed / vmax)
        return max(floor, min(1.0, c.max_blind_travel / (self.measured_latency * vmax)))

    def acting_pose(self, pose: Pose2D, vel: tuple[float, float, float]) -> Pose2D:
        """Where the base will be when a command computed now takes effect: ``pose`` carried on over the
        latency by the twist the base has meanwhile (its measured twist ramping at the acceleration limits
        toward the last command sent); ``pose`` itself when compensation is off or there is no latency."""
        if not self.cfg.latency_compensation or self.latency <= 0.0:
            return pose
        c = self.cfg
        twist = vel if self.last_sent is None else mean_twist(
            vel, self.last_sent, (c.acc_lim_x, c.acc_lim_y, c.acc_lim_theta), self.latency)
        return predict_pose((float(pose[0]), float(pose[1]), float(pose[2])), twist, self.latency)

    def set_path(self, path: NDArray[np.float64], headings: NDArray[np.float64] | None = None) -> None:
        """Follow ``path``; ``headings`` (rad per point, from the footprint-aware planner) is the yaw to hold at
        each point. Passing the current path object again (a restart after a recovery) keeps its headings."""
        if headings is None and path is getattr(self, "path", None):
            headings = self.path_headings
        self.path_headings = None if headings is None else np.asarray(headings, dtype=float).reshape(-1)
        self.path = np.asarray(path, dtype=float).reshape(-1, 2)
        if self.path_headings is not None and len(self.path_headings) != len(self.path):
            raise ValueError(f"{len(self.path_headings)} headings for {len(self.path)} path points")
        seg = np.hypot(*np.diff(self.path, axis=0).T) if len(self.path) > 1 else np.zeros(0)
        self.path_cum: NDArray[np.float64] = np.concatenate([[0.0], np.cumsum(seg)])   # length along path (m)
        self.progress_index = -1     # path point nearest the base at the last step (-1: not yet known)

    def index_ahead(self, i: int, distance: float) -> int:
        """The first path index at least ``distance`` metres along the path past index ``i`` (clamped to the
        path's last point); the shared way other components look ahead along the followed path."""
        return min(len(self.path) - 1, int(np.searchsorted(self.path_cum, self.path_cum[i] + distance)))

    def _closest(self, x: float, y: float) -> int:
        """Nearest path index, searched forward from the last one (so loops in the path don't confuse it)."""
        if self.progress_index < 0:
            lo, hi = 0, len(self.path)
        else:
            lo = self.progress_index
            hi = int(np.searchsorted(self.path_cum, self.path_cum[lo] + 2.0)) + 1
        d = np.hypot(self.path[lo:hi, 0] - x, self.path[lo:hi, 1] - y)
        self.progress_index = lo + int(np.argmin(d))
        return self.progress_index

    def remaining(self, pose: Pose2D) -> float:
        if len(self.path) == 0:
            return 0.0
        i = self._closest(pose[0], pose[1])
        return float(self.path_cum[-1] - self.path_cum[i]
                     + math.hypot(self.path[i, 0] - pose[0], self.path[i, 1] - pose[1]))

    def compute(self, pose: Pose2D, vel: tuple[float, float, float],
                goal: Pose2D, costmap: Costmap, dt: float, xy_reached: bool = False) -> ControlOutput:
        """One control step: pose in the costmap frame, vel = measured body (vx, vy, wz), dt since last step.

        The command is chosen and collision-checked from :meth:`acting_pose`, where it will act, and with a long
        latency under a speed limit that keeps the distance driven blind within ``max_blind_travel``."""
        acting = self.acting_pose(pose, vel)
        limit = self.speed_limit
        self.speed_limit = limit * self.latency_speed_fraction()
        try:
            return self._compute(acting, vel, goal, costmap, dt, xy_reached)
        finally:
            self.speed_limit = limit

    def _compute(self, pose: Pose2D, vel: tuple[float, float, float],
                 goal: Pose2D, costmap: Costmap, dt: float, xy_reached: bool = False) -> ControlOutput:
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
        # --- heading targets: the path's direction at the carrot, and along the stretch the body covers now
        goal_yaw = xy_reached or dgoal < c.rotate_to_goal_dist
        far_yaw = self._path_yaw(i + int(far[0]) if len(far) else len(self.path) - 1, 0.15, th)
        near_yaw = self._path_yaw(i, self._half_length, th, ahead=True)
        if goal_yaw:
            targets = [goal[2]]
        else:
            planned = self.planned_yaw(i)
            passage = self._passage_yaw(i, th, costmap) if planned is None else planned
            order = (passage, near_yaw, far_yaw) if passage is not None else (far_yaw, near_yaw)
            targets = [self._nearest_end(t, th) for t in order]
        err = float(wrap_angle(targets[0] - th))
        # --- translational speed
        v = c.desired_linear_vel * self.speed_limit
        if remaining < c.approach_velocity_scaling_dist:
            v = max(v * remaining / c.approach_velocity_scaling_dist, min(c.min_approach_linear_velocity, v))
        if c.use_cost_regulated_linear_velocity_scaling:
            centre = int(costmap.cost_at(x, y, outside=0))
            if centre != NO_INFORMATION:
                dobs = distance_from_cost(centre, costmap.cfg.footprint.inscribed_radius,
                                          costmap.cfg.cost_scaling_factor)
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
        cmd, blocked = self._choose(vm, targets, pose, vel, costmap, dt)
        return ControlOutput(*cmd, blocked, remaining, "")

    # ---- heading helpers -----------------------------------------------------------------------------
    @property
    def _half_length(self) -> float:
        return float(np.max(np.abs(self.cfg.footprint.polygon[:, 0])))

    def _path_yaw(self, j: int, span: float, default: float, ahead: bool = False) -> float:
        """Direction of the path over ``span`` m ending at index j (or, ahead=True, starting at j)."""
        j = min(max(j, 0), len(self.path) - 1)
        if ahead:
            k = min(int(np.searchsorted(self.path_cum, self.path_cum[j] + span)), len(self.path) - 1)
            seg = self.path[k] - self.path[j]
        else:
            k = max(int(np.searchsorted(self.path_cum, self.path_cum[j] - span)) - 1, 0)
            seg = self.path[j] - self.path[k]
        return math.atan2(seg[1], seg[0]) if float(np.hypot(*seg)) > 1e-6 else default

    def planned_yaw(self, i: int) -> float | None:
        """The planner's heading for the body at path index ``i`` (one point ahead, so a turn in place at a
        point starts as the body arrives there), or None for a path planned without headings."""
        if self.path_headings is None or len(self.path_headings) == 0:
            return None
        return float(self.path_headings[min(i + 1, len(self.path_headings) - 1)])

    def _nearest_end(self, yaw: float, th: float) -> float:
        """With a front/back-symmetric footprint either end may lead: the target closer to the heading now."""
        if self.cfg.allow_reversed_heading and abs(float(wrap_angle(yaw - th))) > math.pi / 2:
            return float(wrap_angle(yaw + math.pi))
        return yaw

    def _passage_yaw(self, i: int, th: float, costmap: Costmap) -> float | None:
        """In a narrow passage on the next stretch of path, the heading whose footprint fits it best.

        A holonomic base need not face where the path goes next: placed at the tightest path point ahead, the
        heading (near the path tangent there) ranked best by :meth:`_rank_passage_yaws` is the one that keeps the
        body off the passage's sides; holding it until the passage is behind is what gets a 0.5 m wide robot
        through a 0.8 m gap or a doorway entered at an angle. None in open space."""
        c = self.cfg
        k = int(np.searchsorted(self.path_cum, self.path_cum[i] + c.passage_lookahead)) + 1
        pts = self.path[i:k]
        cost = costmap.cost_at(pts[:, 0], pts[:, 1], outside=0).astype(int)
        cost[cost == NO_INFORMATION] = 0
        j = int(np.argmax(cost))
        clear = distance_from_cost(int(cost[j]), costmap.cfg.footprint.inscribed_radius,
                                   costmap.cfg.cost_scaling_factor)
        if clear >= c.footprint.circumscribed_radius + c.tight_clearance:
            return None
        tangent = self._path_yaw(max(int(np.searchsorted(self.path_cum, self.path_cum[i + j] - self._half_length)), 0),
                                 2 * self._half_length, th, ahead=True)
        yaws = tangent + np.radians(np.arange(-90.0, 91.0, 10.0))  # holonomic: may cross a passage sideways
        return float(yaws[self._rank_passage_yaws(yaws, tangent, pts[j], costmap)[0]])

    def _rank_passage_yaws(self, yaws: NDArray[np.float64], tangent: float, centre: NDArray[np.float64],
                           costmap: Costmap) -> NDArray[np.int64]:
        """Indices of ``yaws`` best first, for the body centred on ``centre`` (x, y) at each yaw.

        Ranked by, in turn: the lethal cells the outline touches; the body's clearance, its outline's smallest
        distance to a lethal cell in whole costmap cells (more is better); the summed outline cost; closeness to
        the path tangent. Why the clearance before the summed cost: the sum counts how much of the outline lies
        in the inflation, not how close its nearest point comes, and so can prefer a body crossing a 1.1 m doorway
        sideways or skewed (0.2 m or less from a jamb) to one lined up with the crossing (0.3 m from each); the
        most room at the closest point is what keeps a lagging body off the jambs. Why a distance transform
        rather than the largest outline cost: the inflated cost is flat (inscribed) within the inscribed radius,
        0.25 m, which is just where a doorway's jambs are, so it cannot tell those headings apart. Why whole
        cells: clearances less than a cell apart are within the rasterisation's error, so such near-ties still go
        to the summed cost and then the tangent (less turning)."""
        from scipy.ndimage import distance_transform_edt

        # the outline's world points per yaw, once: for the costs and for the clearance lookup below
        cs, sn = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
        px = centre[0] + cs * self._points[None, :, 0] - sn * self._points[None, :, 1]
        py = centre[1] + sn * self._points[None, :, 0] + cs * self._points[None, :, 1]
        fc = costmap.cost_at(px, py, outside=0).astype(float)
        fc[fc == NO_INFORMATION] = 0.0
        hits = (fc == LETHAL).sum(axis=1)
        # distance (cells) to the nearest lethal cell, on a window reaching the inflation radius past the outline
        reach = self.cfg.footprint.circumscribed_radius + costmap.cfg.inflation_radius
        rows, cols = costmap.shape
        c0, r0 = (max(int(v), 0) for v in costmap.world_to_cell(centre[0] - reach, centre[1] - reach))
        c1, r1 = costmap.world_to_cell(centre[0] + reach, centre[1] + reach)
        c1, r1 = min(int(c1) + 1, cols), min(int(r1) + 1, rows)
        clearance = np.zeros(len(yaws))
        lethal = costmap.costs[r0:r1, c0:c1] == LETHAL
        if lethal.any():
            dist = distance_transform_edt(~lethal)
            col, row = costmap.world_to_cell(px, py)
            cells = dist[np.clip(row - r0, 0, r1 - r0 - 1), np.clip(col - c0, 0, c1 - c0 - 1)]
            clearance = np.floor(cells.min(axis=1) + 1e-9)
        return np.lexsort((np.abs(yaws - tangent), fc.sum(axis=1), -clearance, hits))

    # ---- command selection ---------------------------------------------------------------------------
    def _wz_toward(self, target: float, th: float) -> float:
        """Proportional turn, capped so the base can still brake to rest at the target heading."""
        err = float(wrap_angle(target - th))
        cap = min(self.cfg.max_vel_theta, math.sqrt(2.0 * self.cfg.acc_lim_theta * abs(err)))
        return float(np.clip(self.cfg.rotation_gain * err, -cap, cap)) * self.speed_limit

    def _choose(self, vm: NDArray[np.float64], targets: list[float], pose: Pose2D,
                vel: tuple[float, float, float], costmap: Costmap,
                dt: float) -> tuple[tuple[float, float, float], bool]:
        """The first safe candidate in order of preference; candidates are simulated the way the pursuit
        will actually execute them (fixed world-frame translation, rotation that stops at its target), so a
        turn toward a heading is not mistaken for a sweeping arc.

        Preference: full speed toward each heading target, then without turning, then slower, then turning in
        place; finally an escape move that backs away from lethal cells the footprint already touches."""
        th = pose[2]
        cs, sn = math.cos(th), math.sin(th)
        # the acceleration-limited command toward the preferred heading defines the speed actually available
        vx, vy = cs * vm[0] + sn * vm[1], -sn * vm[0] + cs * vm[1]
        lim = max(abs(vx) / (self.cfg.max_vel_x * self.speed_limit),
                  abs(vy) / (self.cfg.max_vel_y * self.speed_limit), 1.0)
        vx, vy, wz0 = self._accel_limit((vx / lim, vy / lim, self._wz_toward(targets[0], th)), vel, dt)
        vw = np.array([cs * vx - sn * vy, sn * vx + cs * vy])
        rot = [(self._wz_toward(t, th), float(wrap_angle(t - th))) for t in dict.fromkeys(targets)]
        rot[0] = (wz0, rot[0][1])
        cands: list[tuple[float, float, float, float]] = []   # world vx, vy, wz, rotation to do (rad)
        for scale in (1.0, 0.5, 0.25):
            w = vw * scale
            if float(np.hypot(*w)) < 1e-6:
                continue
            cands += [(w[0], w[1], wz, turn) for wz, turn in rot]
            cands.append((w[0], w[1], 0.0, 0.0))
        cands += [(0.0, 0.0, wz, turn) for wz, turn in rot if abs(wz) > 1e-6]
        if not cands:
            return (0.0, 0.0, 0.0), False
        arr = np.array(cands)
        ok = ~self.world_trajectory_hits(arr, pose, costmap)
        if ok.any():
            k = int(np.argmax(ok))
            wxv, wyv, wz, _ = cands[k]
            return (cs * wxv + sn * wyv, -sn * wxv + cs * wyv, wz), False
        esc = self._escape(pose, vm, targets[0], costmap)
        if esc is not None:
            wxv, wyv, wz = esc
            return (cs * wxv + sn * wyv, -sn * wxv + cs * wyv, wz), False
        return (0.0, 0.0, 0.0), True

    def _escape(self, pose: Pose2D, aim: NDArray[np.float64], target: float,
                costmap: Costmap) -> tuple[float, float, float] | None:
        """When nothing else is safe but the body is turned away from the heading it needs: a slow translation
        while turning to that heading that adds no lethal contact, preferring the direction of travel. It gets
        the body out of spots where neither turning in place nor going on fits (a doorway entered at an angle).
        None if the heading is already right (then only replanning or a recovery can help) or nothing fits."""
        turn = float(wrap_angle(target - pose[2]))
        if abs(turn) < 0.05:
            return None
        speed = 0.1
        wz = self._wz_toward(target, pose[2])
        cands = np.array([(speed * math.cos(a), speed * math.sin(a), wz, turn)
                          for a in np.linspace(-math.pi, math.pi, 16, endpoint=False)])
        ok = ~self.world_trajectory_hits(cands, pose, costmap)
        if not ok.any():
            return None
        n = float(np.hypot(*aim))
        pref = cands[:, :2] @ (aim / n) if n > 1e-9 else np.zeros(len(cands))
        k = int(np.argmax(np.where(ok, pref, -np.inf)))
        return float(cands[k, 0]), float(cands[k, 1]), float(cands[k, 2])

    def _lethal_cells(self, poses: NDArray[np.float64], costmap: Costmap) -> list[set[int]]:
        """Per pose, the flat indices of the lethal cells the footprint outline touches."""
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        px = poses[:, 0:1] + c * self._points[None, :, 0] - s * self._points[None, :, 1]
        py = poses[:, 1:2] + s * self._points[None, :, 0] + c * self._points[None, :, 1]
        col, row = costmap.world_to_cell(px, py)
        inb = costmap.in_bounds(col, row)
        out = []
        for k in range(len(poses)):
            m = inb[k]
            cells = row[k][m] * costmap.shape[1] + col[k][m]
            out.append({int(v) for v in cells[costmap.costs.flat[cells] == LETHAL]})
        return out

    def world_trajectory_hits(self, cands: NDArray[np.float64], pose: Pose2D,
                              costmap: Costmap, horizon: float | None = None) -> NDArray[np.bool_]:
        """For candidates (K, 4) = world-frame (vx, vy), wz and the rotation after which turning stops, whether
        the simulated footprint touches a lethal cell it does not already touch at the start (those are
        forgiven: the robot cannot do better than not adding contacts, and they are usually noise speckles)."""
        c = self.cfg
        horizon = c.collision_check_time if horizon is None else horizon
        t = self._sample_times(cands[:, :2], cands[:, 2], horizon)
        steps = len(t)
        turn = np.abs(cands[:, 3:4])
        dth = np.sign(cands[:, 2:3]) * np.minimum(np.abs(cands[:, 2:3]) * t[None, :], np.maximum(turn, 0.0))
        dth = np.where(turn > 0, dth, cands[:, 2:3] * t[None, :])
        poses = np.stack([pose[0] + cands[:, 0:1] * t[None, :], pose[1] + cands[:, 1:2] * t[None, :],
                          pose[2] + dth], axis=-1)
        return self._new_contacts(poses.reshape(-1, 3), pose, costmap).reshape(len(cands), steps).any(axis=1)

    def _sample_times(self, v: NDArray[np.float64], wz: NDArray[np.float64], horizon: float) -> NDArray[np.float64]:
        """Simulation times: every ``sim_dt`` to the horizon, and densely over the first ``dense_time`` — the part
        executed before the next check — so that no outline point moves more than half a cell between samples
        (a corner must not tunnel through a cell between two checks)."""
        c = self.cfg
        coarse = np.arange(1, max(1, int(math.ceil(horizon / c.sim_dt))) + 1) * c.sim_dt
        speed = float(np.max(np.hypot(v[:, 0], v[:, 1]) + np.abs(wz) * c.footprint.circumscribed_radius, initial=0.0))
        if speed <= 1e-9:
            return coarse
        ds = min(c.sim_dt, 0.5 * c.footprint_check_resolution / speed)
        dense = np.arange(1, int(math.ceil(min(c.dense_time, horizon) / ds)) + 1) * ds
        return np.unique(np.concatenate([dense, coarse]))

    def _new_contacts(self, poses: NDArray[np.float64], pose: Pose2D,
                      costmap: Costmap) -> NDArray[np.bool_]:
        """Per pose, whether the outline touches a lethal cell that the outline at ``pose`` does not touch."""
        pts = self._points
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        px = poses[:, 0:1] + c * pts[None, :, 0] - s * pts[None, :, 1]
        py = poses[:, 1:2] + s * pts[None, :, 0] + c * pts[None, :, 1]
        col, row = costmap.world_to_cell(px, py)
        inb = costmap.in_bounds(col, row)
        flat = np.where(inb, row * costmap.shape[1] + col, 0)
        lethal = inb & (costmap.costs.flat[flat] == LETHAL)
        start = self._lethal_cells(np.array([pose], dtype=float), costmap)[0]
        if start:
            lethal &= ~np.isin(flat, np.fromiter(start, dtype=np.int64))
        return lethal.any(axis=1)

    def _accel_limit(self, cmd: tuple[float, float, float], vel: tuple[float, float, float],
                     dt: float) -> tuple[float, float, float]:
        c = self.cfg
        dt = max(dt, 1e-3)
        out = []
        for u, v0, a in zip(cmd, vel, (c.acc_lim_x, c.acc_lim_y, c.acc_lim_theta), strict=True):
            out.append(float(np.clip(u, v0 - a * dt, v0 + a * dt)))
        return out[0], out[1], out[2]

    def footprint_cost_sums(self, poses: NDArray[np.float64], costmap: Costmap) -> NDArray[np.float64]:
        """Summed costmap cost under the footprint outline at each pose (N, 3); lethal cells weigh heavily."""
        fc = costmap.footprint_costs(poses, self._points, outside=0).astype(float)
        fc[fc == NO_INFORMATION] = 0.0
        return 1e4 * (fc == LETHAL).sum(axis=1) + fc.sum(axis=1)

    def trajectory_hits(self, cands: NDArray[np.float64], pose: Pose2D,
                        costmap: Costmap, horizon: float | None = None) -> NDArray[np.bool_]:
        """For body-velocity candidates (K, 3) held constant (what the recoveries command), whether the
        forward-simulated footprint touches a lethal cell it is not already touching at the start."""
        c = self.cfg
        horizon = c.collision_check_time if horizon is None else horizon
        t = self._sample_times(cands[:, :2], cands[:, 2], horizon)
        steps = len(t)
        h = np.diff(t, prepend=0.0)[None, :]
        th = pose[2] + cands[:, 2:3] * t[None, :]                        # (K, T)
        cth = np.cos(pose[2] + cands[:, 2:3] * (t[None, :] - h / 2))
        sth = np.sin(pose[2] + cands[:, 2:3] * (t[None, :] - h / 2))
        dx = (cth * cands[:, 0:1] - sth * cands[:, 1:2]) * h
        dy = (sth * cands[:, 0:1] + cth * cands[:, 1:2]) * h
        poses = np.stack([pose[0] + np.cumsum(dx, axis=1), pose[1] + np.cumsum(dy, axis=1), th], axis=-1)
        return self._new_contacts(poses.reshape(-1, 3), pose, costmap).reshape(len(cands), steps).any(axis=1)
