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


@dataclass
class ProgressCheckerConfig:
    """SimpleProgressChecker parameters (``controller_server.<progress checker>``)."""

    required_movement_radius: float = param(
        0.5, "radius the robot must move out of within movement_time_allowance, or it counts as stuck", unit="m",
        gt=0)
    movement_time_allowance: float = param(10.0, "time allowed to move required_movement_radius", unit="s", gt=0)


class ProgressChecker:
    """Fails when the robot has not left a circle of required_movement_radius within the allowance."""

    def __init__(self, cfg: ProgressCheckerConfig | None = None) -> None:
        self.cfg = cfg or ProgressCheckerConfig()
        self._anchor: tuple[float, float] | None = None
        self._t0 = 0.0

    def reset(self) -> None:
        self._anchor = None

    def check(self, now: float, pose: Pose2D) -> bool:
        """True while progressing; False once stuck for longer than the allowance."""
        if self._anchor is None or math.hypot(pose[0] - self._anchor[0], pose[1] - self._anchor[1]) > \
                self.cfg.required_movement_radius:
            self._anchor, self._t0 = (pose[0], pose[1]), now
            return True
        return now - self._t0 <= self.cfg.movement_time_allowance
