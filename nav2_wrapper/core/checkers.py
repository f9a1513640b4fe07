"""Goal and progress checkers with Nav2's semantics and defaults (Simple/StoppedGoalChecker, SimpleProgressChecker)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from robonix_common.geometry import Pose2D, wrap_angle
from robonix_common.params import param


@dataclass
class GoalCheckerConfig:
    """Goal checker parameters (``controller_server.<goal checker>``)."""

    xy_goal_tolerance: float = param(0.25, "distance to the goal that counts as reached", unit="m", gt=0)
    yaw_goal_tolerance: float = param(0.25, "heading error that counts as reached", unit="rad", gt=0)
    stateful: bool = param(True, "once inside the xy tolerance, only the yaw is checked afterwards")
    # StoppedGoalChecker: the goal also needs the base nearly at rest. Without it a goal is declared while the
    # base still turns fast, and it comes to rest outside the yaw tolerance. Set by the plugin, not a YAML key.
    stopped: bool = False
    trans_stopped_velocity: float = param(0.25, "StoppedGoalChecker: translation speed that counts as at rest",
                                          unit="m/s", gt=0)
    rot_stopped_velocity: float = param(0.25, "StoppedGoalChecker: rotation speed that counts as at rest",
                                        unit="rad/s", gt=0)


class GoalChecker:
    def __init__(self, cfg: GoalCheckerConfig | None = None) -> None:
        self.cfg = cfg or GoalCheckerConfig()
        self._xy_latched = False

    def reset(self) -> None:
        self._xy_latched = False

    def xy_reached(self, pose: Pose2D, goal: Pose2D) -> bool:
        if self._xy_latched:
            return True
        ok = math.hypot(pose[0] - goal[0], pose[1] - goal[1]) <= self.cfg.xy_goal_tolerance
        if ok and self.cfg.stateful:
            self._xy_latched = True
        return ok

    def is_goal_reached(self, pose: Pose2D, goal: Pose2D, vel: tuple[float, float, float] | None = None) -> bool:
        """Within the xy and yaw tolerances and, for a stopped checker, with body velocity ``vel`` at rest."""
        if not self.xy_reached(pose, goal):
            return False
        if abs(float(wrap_angle(pose[2] - goal[2]))) > self.cfg.yaw_goal_tolerance:
            return False
        c = self.cfg
        if vel is None or not c.stopped:
            return True
        return math.hypot(vel[0], vel[1]) <= c.trans_stopped_velocity and abs(vel[2]) <= c.rot_stopped_velocity


OK, SLOW, BLOCKED, STUCK = "ok", "slow", "blocked", "stuck"


@dataclass
class ProgressCheckerConfig:
    """SimpleProgressChecker parameters (``controller_server.<progress checker>``), plus the blocked/slow split."""

    required_movement_radius: float = param(
        0.5, "radius the robot must move out of within movement_time_allowance, or it counts as stuck", unit="m",
        gt=0)
    movement_time_allowance: float = param(10.0, "time allowed to move required_movement_radius", unit="s", gt=0)
    slow_min_progress: float = param(
        0.10, "progress along the path within the allowance that makes a robot that missed the radius 'slow' "
        "(allowance extended) rather than stuck", unit="m", gt=0)
    slow_extension_max: float = param(10.0, "the most a slow robot's allowance is extended by", unit="s", ge=0)
    blocked_time_allowance: float = param(
        3.0, "time the robot may stay blocked (not moving while pressed against an obstacle toward the path, or "
        "not realising its command) before a recovery", unit="s", gt=0)
    blocked_speed: float = param(0.03, "below this measured speed the robot counts as not moving", unit="m/s",
                                 gt=0)
    blocked_min_command: float = param(
        0.04, "commanded speed that must be realised: a robot commanded at least this (mean over the last half "
        "second: MPPI's commands from standstill hover around 0.05 m/s and dip below it) that does not move is "
        "blocked", unit="m/s", gt=0)


@dataclass(frozen=True)
class Progress:
    """One progress check: ``state`` is ok, slow (ok, allowance extended), blocked or stuck (both: recover)."""

    state: str
    detail: str = ""

    @property
    def ok(self) -> bool:
        return self.state in (OK, SLOW)


class ProgressChecker:
    """Fails when the robot has not left a circle of required_movement_radius within the allowance, unless
    it is *slow* — moving, and gaining ``slow_min_progress`` along the path — which earns a bounded extension.
    Fails early as *blocked* when, for ``blocked_time_allowance``, the robot does not move although it is
    pressed against an obstacle toward the path or does not realise a clear command: waiting longer cannot
    help there, an escape can."""

    def __init__(self, cfg: ProgressCheckerConfig | None = None) -> None:
        self.cfg = cfg or ProgressCheckerConfig()
        self.reset()

    def reset(self) -> None:
        self._anchor: tuple[float, float] | None = None
        self._t0 = 0.0
        self._rem0: float | None = None
        self._best_rem: float | None = None
        self._hist: list[tuple[float, float, float]] = []
        self._cmds: list[tuple[float, float]] = []
        self._blocked_since: float | None = None

    def check(self, now: float, pose: Pose2D) -> bool:
        """True while progressing; False once stuck for longer than the allowance (Nav2's simple checker)."""
        return self.assess(now, pose).ok

    def _speed(self, now: float, pose: Pose2D) -> float | None:
        """Measured speed over the last half second (None until that much history)."""
        self._hist.append((now, pose[0], pose[1]))
        while len(self._hist) > 2 and self._hist[1][0] <= now - 0.5:
            self._hist.pop(0)
        t, x, y = self._hist[0]
        if now - t < 0.25:
            return None
        return math.hypot(pose[0] - x, pose[1] - y) / (now - t)

    def _mean_command(self, now: float, command: float | None) -> float | None:
        """Mean commanded speed over the last half second: a sampling controller's single commands jitter."""
        if command is None:
            return None
        self._cmds.append((now, command))
        while len(self._cmds) > 1 and self._cmds[0][0] < now - 0.5:
            self._cmds.pop(0)
        return sum(v for _, v in self._cmds) / len(self._cmds)

    def _blocked(self, now: float, speed: float | None, command: float | None, pressed: bool) -> str | None:
        c = self.cfg
        command = self._mean_command(now, command)
        why = None
        if speed is not None and speed < c.blocked_speed:
            if pressed:
                why = "pressed against an obstacle toward the path"
            # Hysteresis: once counting, a jittering command may dip to half the threshold without a restart.
            elif command is not None and command >= c.blocked_min_command * (
                    0.5 if self._blocked_since is not None else 1.0):
                why = f"commanded {command:.2f} m/s but moving {speed:.2f} m/s"
        if why is None:
            self._blocked_since = None
            return None
        if self._blocked_since is None:
            self._blocked_since = now
        return why if now - self._blocked_since >= c.blocked_time_allowance else None

    def assess(self, now: float, pose: Pose2D, *, command: float | None = None, remaining: float | None = None,
               pressed: bool = False) -> Progress:
        """Classify progress. ``command``: the speed last commanded (m/s); ``remaining``: path length left
        (m, the controller's); ``pressed``: the footprint is at the clearance margin toward the path. Without
        them this is Nav2's SimpleProgressChecker."""
        c = self.cfg
        speed = self._speed(now, pose)
        if remaining is not None:
            self._best_rem = remaining if self._best_rem is None else min(self._best_rem, remaining)
        if self._anchor is None or math.hypot(pose[0] - self._anchor[0], pose[1] - self._anchor[1]) > \
                c.required_movement_radius:
            self._anchor, self._t0, self._rem0 = (pose[0], pose[1]), now, remaining
            self._best_rem = remaining
            self._blocked_since = None
            return Progress(OK)
        why = self._blocked(now, speed, command, pressed)
        if why is not None:
            return Progress(BLOCKED, f"blocked: {why} for {now - self._blocked_since:.1f} s")  # type: ignore[operator]
        waited = now - self._t0
        if waited <= c.movement_time_allowance:
            return Progress(OK)
        gained = (self._rem0 - self._best_rem) if self._rem0 is not None and self._best_rem is not None else 0.0
        moving = speed is not None and speed >= c.blocked_speed
        if gained >= c.slow_min_progress and moving and waited <= c.movement_time_allowance + c.slow_extension_max:
            return Progress(SLOW, f"slow: {gained:.2f} m along the path in {waited:.0f} s, allowance extended "
                                  f"to {c.movement_time_allowance + c.slow_extension_max:.0f} s")
        return Progress(STUCK, f"no progress ({c.required_movement_radius:.2f} m in {waited:.0f} s; "
                               f"{gained:.2f} m along the path)")
