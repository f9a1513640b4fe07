"""Recovery behaviours in Nav2's default order (clear costmaps, spin, wait, back up), each a small state
machine that emits velocity commands, and a round-robin sequencer with a retry budget."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from robonix_common.geometry import Pose2D, wrap_angle
from robonix_common.params import param

from .controller import HolonomicController
from .costmap import Costmap

BEHAVIORS = ("clear_costmaps", "spin", "wait", "backup")


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


class RecoverySequence:
    """Round-robin over the behaviours; each run spends one retry of the budget (Nav2 RoundRobin + RecoveryNode)."""

    def __init__(self, cfg: RecoveryConfig, clear: Callable[[], None]) -> None:
        self.cfg = cfg
        make = {"clear_costmaps": lambda: ClearCostmaps(cfg, clear), "spin": lambda: Spin(cfg),
                "wait": lambda: Wait(cfg), "backup": lambda: BackUp(cfg)}
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

    @property
    def exhausted(self) -> bool:
        return self.used >= self.cfg.number_of_retries

    def begin(self, now: float, pose: Pose2D) -> Behavior | None:
        """Start the next behaviour, or None when the budget is spent."""
        if self.exhausted or not self._behaviors:
            return None
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
            self.active = None
        return s
