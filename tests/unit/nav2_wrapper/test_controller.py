"""Controller (closed loop with an integrator), goal/progress checkers, recovery order and budget."""

import math

import numpy as np
import pytest

from nav2_wrapper.core import (
    ControllerConfig,
    Costmap,
    CostmapConfig,
    GlobalPlanner,
    GoalChecker,
    GoalCheckerConfig,
    HolonomicController,
    ProgressChecker,
    RecoveryConfig,
    RecoverySequence,
)
from nav2_wrapper.robot_io import load_footprint

from .sim import footprint_collides, room

FP = load_footprint()
MAPS = {
    "open": (room(8, 6), (1.0, 1.0, 0.0), (7.0, 5.0, math.pi / 2)),
    "wall": (room(10, 6, boxes=((4.5, 0, 5.0, 4.0),)), (1.0, 1.0, 0.0), (8.5, 1.0, 0.0)),
    "corridor": (room(10, 6, boxes=((0, 2.0, 8.0, 2.6), (2.0, 3.8, 10, 4.4))), (1.0, 1.0, 0.0), (1.0, 5.2, math.pi)),
}


def _follow(grid, start, goal, steps=1200, dt=0.05):
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    plan = GlobalPlanner().plan(cm, start[:2], goal[:2])
    assert plan.ok, plan.reason
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    ctrl.set_path(plan.path)
    gc = GoalChecker()
    x, y, th = start
    vel = (0.0, 0.0, 0.0)
    for _ in range(steps):
        if gc.is_goal_reached((x, y, th), goal):
            return (x, y, th), True
        out = ctrl.compute((x, y, th), vel, goal, cm, dt, gc.xy_reached((x, y, th), goal))
        assert abs(out.vx) <= 0.5 + 1e-9
        assert abs(out.vy) <= 0.5 + 1e-9
        assert abs(out.wz) <= 1.9 + 1e-9
        assert abs(out.vx - vel[0]) <= 1.5 * dt + 1e-9 or out.blocked       # acceleration limit
        c, s = math.cos(th), math.sin(th)
        x, y, th = x + (c * out.vx - s * out.vy) * dt, y + (s * out.vx + c * out.vy) * dt, th + out.wz * dt
        vel = (out.vx, out.vy, out.wz)
        assert not footprint_collides(grid, (x, y, th)), f"collision at {(x, y, th)}"
    return (x, y, th), False


@pytest.mark.parametrize("name", sorted(MAPS))
def test_controller_reaches_goal_without_collision(name):
    grid, start, goal = MAPS[name]
    (x, y, th), ok = _follow(grid, start, goal)
    assert ok, f"did not reach {goal}, ended at {(x, y, th)}"


def test_speed_limit_percentage_scales_commands():
    grid, start, goal = MAPS["open"]
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    ctrl.set_path(GlobalPlanner().plan(cm, start[:2], goal[:2]).path)
    ctrl.set_speed_limit(40.0)
    out = ctrl.compute((2.0, 2.0, math.atan2(4, 6)), (0.2, 0.0, 0.0), goal, cm, 1.0)
    assert math.hypot(out.vx, out.vy) <= 0.2 + 1e-9


def test_controller_stops_before_an_obstacle():
    grid = room(6, 4, boxes=((2.5, 0, 3.0, 4.0),))           # wall across the room
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    ctrl.set_path(np.stack([np.linspace(1.5, 5.0, 80), np.full(80, 2.0)], axis=1))   # path straight through it
    out = ctrl.compute((2.05, 2.0, 0.0), (0.5, 0.0, 0.0), (5.0, 2.0, 0.0), cm, 0.05)
    assert out.blocked
    assert (out.vx, out.vy) == (0.0, 0.0)


def test_goal_checker_tolerances_and_stateful_latch():
    gc = GoalChecker(GoalCheckerConfig(xy_goal_tolerance=0.25, yaw_goal_tolerance=0.25))
    assert not gc.is_goal_reached((0.3, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert not gc.is_goal_reached((0.2, 0.0, 1.0), (0.0, 0.0, 0.0))     # xy ok, yaw not
    assert gc.is_goal_reached((0.3, 0.0, 0.1), (0.0, 0.0, 0.0))         # latched xy, yaw now ok
    gc.reset()
    assert not gc.is_goal_reached((0.3, 0.0, 0.1), (0.0, 0.0, 0.0))


def test_progress_checker_nav2_defaults():
    pc = ProgressChecker()
    assert pc.cfg.required_movement_radius == 0.5
    assert pc.cfg.movement_time_allowance == 10.0
    assert pc.check(0.0, (0.0, 0.0, 0.0))
    assert pc.check(9.9, (0.4, 0.0, 0.0))
    assert not pc.check(10.1, (0.4, 0.0, 0.0))
    assert pc.check(10.2, (0.6, 0.0, 0.0))                               # moved out: progress again
    assert pc.check(20.0, (0.6, 0.1, 0.0))


def test_recovery_order_budget_and_commands():
    grid = room(6, 6)
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    cleared = []
    seq = RecoverySequence(RecoveryConfig(number_of_retries=6), lambda: cleared.append(True))
    pose = [3.0, 3.0, 0.0]
    t = 0.0
    names = []
    while (beh := seq.begin(t, tuple(pose))) is not None:
        names.append(beh.name)
        for _ in range(400):
            s = seq.step(t, tuple(pose), cm, ctrl)
            if s.done:
                assert s.ok, s.detail
                break
            if beh.name == "wait":
                assert (s.vx, s.vy, s.wz) == (0.0, 0.0, 0.0)
            if beh.name == "spin":
                assert s.wz > 0
                assert s.vx == 0.0
            if beh.name == "backup":
                assert s.vx < 0
                assert s.wz == 0.0
            pose[0] += (math.cos(pose[2]) * s.vx - math.sin(pose[2]) * s.vy) * 0.1
            pose[1] += (math.sin(pose[2]) * s.vx + math.cos(pose[2]) * s.vy) * 0.1
            pose[2] += s.wz * 0.1
            t += 0.1
    assert names == ["escape", "clear_costmaps", "spin", "wait", "backup", "escape"]
    assert seq.exhausted
    assert len(cleared) == 1


def test_spin_refuses_when_it_would_collide():
    grid = room(6, 6, boxes=((3.4, 0, 3.6, 6),))               # wall face at x=3.35: front clear, corners not
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    seq = RecoverySequence(RecoveryConfig(behaviors=("spin",)), lambda: None)
    seq.begin(0.0, (2.97, 3.0, 0.0))
    s = seq.step(0.0, (2.97, 3.0, 0.0), cm, HolonomicController(ControllerConfig(footprint=FP)))
    assert s.done
    assert not s.ok
    assert "collide" in s.detail
