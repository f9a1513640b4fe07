"""A goal is reached only once the base is at rest (StoppedGoalChecker), and turning can brake in time."""

from __future__ import annotations

import math

from nav2_wrapper.core.checkers import GoalChecker, GoalCheckerConfig
from nav2_wrapper.core.controller import ControllerConfig, HolonomicController
from nav2_wrapper.params import load_params
from nav2_wrapper.robot_io import load_footprint


def test_stopped_checker_requires_rest() -> None:
    gc = GoalChecker(GoalCheckerConfig(stopped=True, trans_stopped_velocity=0.25, rot_stopped_velocity=0.25))
    goal = (1.0, 1.0, 0.0)
    pose = (1.1, 1.0, 0.1)
    assert not gc.is_goal_reached(pose, goal, (0.0, 0.0, 1.0))   # still turning fast
    assert not gc.is_goal_reached(pose, goal, (0.4, 0.0, 0.0))   # still driving
    assert gc.is_goal_reached(pose, goal, (0.1, 0.1, 0.2))
    simple = GoalChecker(GoalCheckerConfig())
    assert simple.is_goal_reached(pose, goal, (0.0, 0.0, 1.5))   # Simple checker ignores velocity


def test_turn_rate_is_capped_so_the_base_can_brake() -> None:
    cfg = ControllerConfig(footprint=load_footprint())
    ctl = HolonomicController(cfg)
    for err in (0.05, 0.2, 0.6):
        wz = abs(ctl._wz_toward(err, 0.0))
        # Braking from wz at acc_lim_theta covers wz^2 / (2 a): never more than the remaining error.
        assert wz ** 2 / (2 * cfg.acc_lim_theta) <= err + 1e-9
    assert math.isclose(abs(ctl._wz_toward(3.0, 0.0)), cfg.max_vel_theta)


def test_profiles_use_the_stopped_checker() -> None:
    for profile in ("sim", "slam", "default"):
        loaded = load_params(profile, map_topic="/map", odom_topic="/odom", scan_topic="/scan")
        gc = loaded.config.goal_checker
        assert gc.stopped, profile
        assert gc.trans_stopped_velocity == 0.25, profile
        assert gc.rot_stopped_velocity == 0.25, profile
