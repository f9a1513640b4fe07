"""Goal and progress checkers with Nav2's semantics and defaults (Simple/StoppedGoalChecker, SimpleProgressChecker)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from robonix_common.geometry import wrap_angle


@dataclass
class GoalCheckerConfig:
    xy_goal_tolerance: float = 0.25
    yaw_goal_tolerance: float = 0.25
    stateful: bool = True   # once inside the xy tolerance, only the yaw is checked afterwards (Nav2 default)
    # StoppedGoalChecker: the goal also needs the base nearly at rest (None = SimpleGoalChecker). Without it a
    # goal is declared while the base still turns fast, and it comes to rest outside the yaw tolerance.
    trans_stopped_velocity: float | None = None
    rot_stopped_velocity: float | None = None


class GoalChecker:
    def __init__(self, cfg: GoalCheckerConfig | None = None) -> None:
        self.cfg = cfg or GoalCheckerConfig()
        self._xy_latched = False

    def reset(self) -> None:
        self._xy_latched = False

    def xy_reached(self, pose: tuple[float, float, float], goal: tuple[float, float, float]) -> bool:
        if self._xy_latched:
            return True
        ok = math.hypot(pose[0] - goal[0], pose[1] - goal[1]) <= self.cfg.xy_goal_tolerance
        if ok and self.cfg.stateful:
            self._xy_latched = True
        return ok

    def is_goal_reached(self, pose: tuple[float, float, float], goal: tuple[float, float, float],
                        vel: tuple[float, float, float] | None = None) -> bool:
        """Within the xy and yaw tolerances and, for a stopped checker, with body velocity ``vel`` at rest."""
        if not self.xy_reached(pose, goal):
            return False
        if abs(float(wrap_angle(pose[2] - goal[2]))) > self.cfg.yaw_goal_tolerance:
            return False
        c = self.cfg
        if vel is not None and c.trans_stopped_velocity is not None and \
                math.hypot(vel[0], vel[1]) > c.trans_stopped_velocity:
            return False
        return vel is None or c.rot_stopped_velocity is None or abs(vel[2]) <= c.rot_stopped_velocity


@dataclass
class ProgressCheckerConfig:
    required_movement_radius: float = 0.5
    movement_time_allowance: float = 10.0


class ProgressChecker:
    """Fails when the robot has not left a circle of required_movement_radius within the allowance."""

    def __init__(self, cfg: ProgressCheckerConfig | None = None) -> None:
        self.cfg = cfg or ProgressCheckerConfig()
        self._anchor: tuple[float, float] | None = None
        self._t0 = 0.0

    def reset(self) -> None:
        self._anchor = None

    def check(self, now: float, pose: tuple[float, float, float]) -> bool:
        """True while progressing; False once stuck for longer than the allowance."""
        if self._anchor is None or math.hypot(pose[0] - self._anchor[0], pose[1] - self._anchor[1]) > \
                self.cfg.required_movement_radius:
            self._anchor, self._t0 = (pose[0], pose[1]), now
            return True
        return now - self._t0 <= self.cfg.movement_time_allowance
