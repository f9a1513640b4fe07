"""Recovery behaviours (escape, then Nav2's default order: clear costmaps, spin, wait, back up), each a small
state machine that emits velocity commands, and a round-robin sequencer with a retry budget.

The escape (:mod:`.escape`) comes first because in clutter the usual failure is a base wedged a few cm from
a post, which none of Nav2's fixed motions reliably gets out of; a caller that knows the base is blocked
(rather than lost or slow) asks for it directly with ``begin(..., prefer="escape")``."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import Pose2D, wrap_angle
from robonix_common.params import param

from . import escape as esc
from .controller import HolonomicController
from .costmap import Costmap

BEHAVIORS = ("escape", "clear_costmaps", "spin", "wait", "backup")


@dataclass
class RecoveryConfig:
    """Recovery parameters: the sequence from ``bt_navigator``, the motion limits from ``behavior_server``."""

    number_of_retries: int = param(6, "recoveries a goal may use before it fails (BT RecoveryNode)", ge=0)
    behaviors: tuple[str, ...] = param(BEHAVIORS, "recoveries run round-robin, in this order", choices=BEHAVIORS)
    spin_dist: float = param(1.57, "angle a spin turns", unit="rad", gt=0)
    max_rotational_vel: float = param(1.0, "spin turn rate limit", unit="rad/s", gt=0)
    min_rotational_vel: float = param(0.4, "spin turn rate floor", unit="rad/s", gt=0)
    rotational_acc_lim: float = param(3.2, "spin deceleration used to stop at spin_dist", unit="rad/s^2", gt=0)
    wait_duration: float = param(5.0, "how long a wait recovery stands still", unit="s", ge=0)
    backup_dist: float = param(0.30, "distance a backup moves away from what blocks the robot", unit="m", gt=0)
    backup_speed: float = param(0.05, "backup speed", unit="m/s", gt=0)
    time_allowance: float = param(10.0, "a spin or backup that takes longer fails", unit="s", gt=0)
    simulate_ahead_time: float = param(2.0, "collision look-ahead of spin and backup", unit="s", gt=0)
    escape_dist: float = param(0.15, "longest translation an escape motion makes", unit="m", gt=0, le=1.0)
    escape_turn: float = param(0.35, "rotation step of escape motions (in place up to twice this)", unit="rad",
                               gt=0, le=1.57)
    escape_directions: int = param(16, "translation directions escape samples over the full circle", ge=4, le=72)
    escape_speed: float = param(0.10, "escape translation speed", unit="m/s", gt=0)
    escape_margin: float = param(
        0.05, "footprint clearance below which the base counts as wedged; an escape never brings it closer than "
        "this or than it already is", unit="m", ge=0)
    escape_enough: float = param(0.12, "escape clearance beyond which more does not matter (then the path "
                                 "direction decides)", unit="m", gt=0)
    escape_tolerance: float = param(0.01, "clearance an escape may lose to sensor noise", unit="m", ge=0)
    escape_reach: float = param(1.2, "obstacles within this of the base centre are considered", unit="m", gt=0)


@dataclass
class Step:
    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0
    done: bool = False
    ok: bool = True
    detail: str = ""


class Behavior:
    name = "behavior"

    def __init__(self, cfg: RecoveryConfig) -> None:
        self.cfg = cfg
        self.t0 = 0.0

    def start(self, now: float, pose: Pose2D) -> None:
        self.t0 = now

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        raise NotImplementedError

    def _timed_out(self, now: float) -> bool:
        return now - self.t0 > self.cfg.time_allowance


class ClearCostmaps(Behavior):
    name = "clear_costmaps"

    def __init__(self, cfg: RecoveryConfig, clear: Callable[[], None]) -> None:
        super().__init__(cfg)
        self._clear = clear

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        self._clear()
        return Step(done=True, detail="cleared local and global costmaps")


class Spin(Behavior):
    name = "spin"

    def start(self, now: float, pose: Pose2D) -> None:
        super().start(now, pose)
        self._last, self._turned = pose[2], 0.0

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        c = self.cfg
        self._turned += abs(float(wrap_angle(pose[2] - self._last)))
        self._last = pose[2]
        left = c.spin_dist - self._turned
        if left <= 0.0:
            return Step(done=True, detail=f"spun {self._turned:.2f} rad")
        if self._timed_out(now):
            return Step(done=True, ok=False, detail="spin timed out")
        w = min(c.max_rotational_vel, max(c.min_rotational_vel, math.sqrt(2.0 * c.rotational_acc_lim * left)))
        horizon = min(c.simulate_ahead_time, left / w)
        if ctrl.trajectory_hits(np.array([[0.0, 0.0, w]]), pose, costmap, horizon)[0]:
            return Step(done=True, ok=False, detail="spin would collide")
        return Step(0.0, 0.0, w)


class Wait(Behavior):
    name = "wait"

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        if now - self.t0 >= self.cfg.wait_duration:
            return Step(done=True, detail=f"waited {self.cfg.wait_duration:.1f} s")
        return Step()


class BackUp(Behavior):
    """Back away from what blocks the robot. A holonomic base is not limited to body-backwards (which may
    point into the very wall it touches): it takes the body-frame direction, straight back first, that adds
    no new contact and leaves the footprint in the lowest cost, and holds it for ``backup_dist``."""

    name = "backup"
    #: Candidate directions (body frame, rad), in order of preference: back, oblique back, sideways, oblique.
    DIRECTIONS = tuple(math.radians(a) for a in (180, 135, -135, 90, -90, 45, -45))

    def start(self, now: float, pose: Pose2D) -> None:
        super().start(now, pose)
        self._origin = (pose[0], pose[1])
        self._dir: tuple[float, float] | None = None

    def _choose(self, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> tuple[float, float] | None:
        c = self.cfg
        cands = np.array([[c.backup_speed * math.cos(a), c.backup_speed * math.sin(a), 0.0] for a in self.DIRECTIONS])
        horizon = min(c.simulate_ahead_time, c.backup_dist / c.backup_speed)
        hits = ctrl.trajectory_hits(cands, pose, costmap, horizon)
        cth, sth = math.cos(pose[2]), math.sin(pose[2])
        d = c.backup_dist / c.backup_speed
        ends = np.array([[pose[0] + (cth * v[0] - sth * v[1]) * d, pose[1] + (sth * v[0] + cth * v[1]) * d, pose[2]]
                         for v in cands])
        cost = ctrl.footprint_cost_sums(ends, costmap)
        best = None
        for k in range(len(cands)):  # preference order breaks ties; straight back wins unless it is worse
            if not hits[k] and (best is None or cost[k] < cost[best] - 1e-9):
                best = k
        return None if best is None else (float(cands[best, 0]), float(cands[best, 1]))

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        c = self.cfg
        moved = math.hypot(pose[0] - self._origin[0], pose[1] - self._origin[1])
        if moved >= c.backup_dist:
            return Step(done=True, detail=f"backed up {moved:.2f} m")
        if self._timed_out(now):
            return Step(done=True, ok=False, detail="backup timed out")
        if self._dir is None:
            self._dir = self._choose(pose, costmap, ctrl)
            if self._dir is None:
                return Step(done=True, ok=False, detail="backup would collide in every direction")
        horizon = min(c.simulate_ahead_time, (c.backup_dist - moved) / c.backup_speed)
        if ctrl.trajectory_hits(np.array([[self._dir[0], self._dir[1], 0.0]]), pose, costmap, horizon)[0]:
            return Step(done=True, ok=False, detail="backup would collide")
        return Step(self._dir[0], self._dir[1], 0.0)


class Escape(Behavior):
    """Leave a wedge by the short holonomic motion that most increases the footprint's true clearance
    (:func:`.escape.choose`), tie-broken toward the path. The motion is a target pose a few cm away, driven to
    at ``escape_speed``; every step re-checks the rest of it against the newest costmap and scan, and picks
    again (a few times at most) if it has become unsafe. Reports when no sampled motion is free."""

    name = "escape"
    MAX_CHOICES = 3

    def __init__(self, cfg: RecoveryConfig, scan_points: Callable[[], NDArray[np.float64] | None]) -> None:
        super().__init__(cfg)
        self._scan_points = scan_points
        self._motions = esc.candidate_motions(cfg.escape_dist, cfg.escape_turn, cfg.escape_directions)

    def start(self, now: float, pose: Pose2D) -> None:
        super().start(now, pose)
        self._target: Pose2D | None = None
        self._choices = 0
        self._first: esc.Choice | None = None
        self._deadline = math.inf

    def _obstacles(self, pose: Pose2D, costmap: Costmap) -> esc.Obstacles:
        return esc.gather_obstacles(costmap, pose[0], pose[1], self.cfg.escape_reach, self._scan_points())

    @staticmethod
    def _aim(pose: Pose2D, ctrl: HolonomicController) -> tuple[float, float] | None:
        """World direction toward the path half a metre past its point nearest the base."""
        p = ctrl.path
        if len(p) == 0:
            return None
        i = int(np.argmin(np.hypot(p[:, 0] - pose[0], p[:, 1] - pose[1])))
        j = ctrl.index_ahead(i, 0.5)
        return float(p[j, 0] - pose[0]), float(p[j, 1] - pose[1])

    def _choose(self, pose: Pose2D, obs: esc.Obstacles, ctrl: HolonomicController) -> esc.Choice:
        c = self.cfg
        ch = esc.choose(ctrl.cfg.footprint.polygon, pose, obs, self._motions, margin=c.escape_margin,
                        tolerance=c.escape_tolerance, enough=c.escape_enough, aim=self._aim(pose, ctrl))
        self._choices += 1
        self._first = self._first or ch
        if ch.motion is not None:
            m = ch.motion
            self._target = (pose[0] + m.dx, pose[1] + m.dy, pose[2] + m.dth)
            turn_rate = self.cfg.escape_speed / max(ctrl.cfg.footprint.circumscribed_radius, 1e-3)
            nominal = max(math.hypot(m.dx, m.dy) / self.cfg.escape_speed, abs(m.dth) / turn_rate)
            self._deadline = self.t0 + 2.0 * nominal + 1.0 if self._choices == 1 else self._deadline + nominal
        return ch

    def _still_free(self, pose: Pose2D, obs: esc.Obstacles, ctrl: HolonomicController) -> bool:
        assert self._target is not None
        c, poly = self.cfg, ctrl.cfg.footprint.polygon
        rest = esc.Motion(self._target[0] - pose[0], self._target[1] - pose[1],
                          float(wrap_angle(self._target[2] - pose[2])))
        n = esc.samples_for([rest], ctrl.cfg.footprint.circumscribed_radius, 0.01)
        now_c = float(esc.clearance(poly, np.array([pose]), obs)[0])
        return bool(esc.clearance(poly, rest.poses(pose, n), obs).min()
                    >= esc.allowed_floor(now_c, c.escape_margin, c.escape_tolerance))

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        c = self.cfg
        obs = self._obstacles(pose, costmap)
        if self._target is None:
            ch = self._choose(pose, obs, ctrl)
            if ch.motion is None:
                return Step(done=True, ok=False, detail=f"escape: none of {ch.candidates} motions is collision-free "
                                                        f"(footprint clearance {ch.start_clearance:.3f} m)")
        assert self._target is not None
        left = math.hypot(self._target[0] - pose[0], self._target[1] - pose[1])
        if left < 0.01 and abs(float(wrap_angle(self._target[2] - pose[2]))) < 0.03:
            return Step(done=True, detail=self._summary(pose, obs, ctrl, "escaped"))
        if now > self._deadline:        # odometry noise or a slow base: near enough, the navigator takes over
            return Step(done=True, detail=self._summary(pose, obs, ctrl, "escaped (stopped short)"))
        if self._timed_out(now):
            return Step(done=True, ok=False, detail=self._summary(pose, obs, ctrl, "escape timed out"))
        if not self._still_free(pose, obs, ctrl) and (
                self._choices >= self.MAX_CHOICES or self._choose(pose, obs, ctrl).motion is None):
            return Step(done=True, ok=False, detail=self._summary(pose, obs, ctrl, "escape blocked on the way"))
        turn_rate = c.escape_speed / max(ctrl.cfg.footprint.circumscribed_radius, 1e-3)
        vx, vy, wz = esc.body_command(pose, self._target, c.escape_speed, turn_rate, 0.05)
        return Step(vx, vy, wz)

    def _summary(self, pose: Pose2D, obs: esc.Obstacles, ctrl: HolonomicController, what: str) -> str:
        now_c = float(esc.clearance(ctrl.cfg.footprint.polygon, np.array([pose]), obs)[0])
        first = self._first
        how = first.motion.describe() if first is not None and first.motion is not None else "?"
        before = first.start_clearance if first is not None else now_c
        return f"{what}: {how}; footprint clearance {before:.3f} -> {now_c:.3f} m"


class RecoverySequence:
    """Round-robin over the behaviours; each run spends one retry of the budget (Nav2 RoundRobin + RecoveryNode)."""

    def __init__(self, cfg: RecoveryConfig, clear: Callable[[], None],
                 scan_points: Callable[[], NDArray[np.float64] | None] = lambda: None) -> None:
        """``scan_points``: the latest scan's returns as costmap-frame points (N, 2), or None; the escape
        measures clearance to them as well as to the local costmap's lethal cells."""
        self.cfg = cfg
        make = {"clear_costmaps": lambda: ClearCostmaps(cfg, clear), "spin": lambda: Spin(cfg),
                "wait": lambda: Wait(cfg), "backup": lambda: BackUp(cfg),
                "escape": lambda: Escape(cfg, scan_points)}
        unknown = [b for b in cfg.behaviors if b not in make]
        if unknown:
            raise ValueError(f"unknown recovery behaviour(s) {unknown}; known: {sorted(make)}")
        self._behaviors = [make[b]() for b in cfg.behaviors]
        self.reset()

    def reset(self) -> None:
        self.used = 0
        self._next = 0
        self.active: Behavior | None = None
        self.history: list[str] = []
        self._last_failed: str | None = None

    @property
    def exhausted(self) -> bool:
        return self.used >= self.cfg.number_of_retries

    def begin(self, now: float, pose: Pose2D, prefer: str | None = None) -> Behavior | None:
        """Start the next behaviour, or None when the budget is spent. ``prefer`` names a configured
        behaviour to run now instead (the round-robin position is kept), unless its last run failed — then
        the round-robin tries something else; it spends a retry all the same."""
        if self.exhausted or not self._behaviors:
            return None
        chosen = [b for b in self._behaviors if b.name == prefer and b.name != self._last_failed]
        if chosen:
            self.active = chosen[0]
        else:
            self.active = self._behaviors[self._next % len(self._behaviors)]
            self._next += 1
        self.used += 1
        self.history.append(self.active.name)
        self.active.start(now, pose)
        return self.active

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: HolonomicController) -> Step:
        if self.active is None:
            return Step(done=True, ok=False, detail="no recovery running")
        s = self.active.step(now, pose, costmap, ctrl)
        if s.done:
            self._last_failed = None if s.ok else self.active.name
            self.active = None
        return s
