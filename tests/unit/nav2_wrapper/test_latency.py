"""Control latency: the pose prediction, the latency estimate, and a closed loop whose commands act late.

The closed loop here is the multi-process system's timing in miniature: the controller sees the pose
``delay / 2`` old and its command acts ``delay / 2`` later, while the base follows the commands already sent
at its acceleration limits. Contacts are judged on the true grid with the real footprint. Everything is
sim time, so the results do not depend on the machine's speed.
"""

from __future__ import annotations

import collections
import math

import numpy as np
import pytest

from nav2_wrapper.core import ControllerConfig, Costmap, CostmapConfig, GlobalPlanner, GoalChecker, HolonomicController
from nav2_wrapper.core.latency import LatencyEstimate, mean_twist, predict_pose
from nav2_wrapper.core.mppi import MppiConfig, MppiController
from nav2_wrapper.robot_io import load_footprint

from .sim import footprint_collides, room

FP = load_footprint()
ACC = (1.5, 1.5, 3.0)
CORRIDOR = (room(10, 6, boxes=((0, 2.0, 8.0, 2.6), (2.0, 3.8, 10, 4.4))), (1.0, 1.0, 0.0), (1.0, 5.2, math.pi))


def _euler(pose, vel, dt, n=20000):
    x, y, th = pose
    h = dt / n
    for _ in range(n):
        c, s = math.cos(th + vel[2] * h / 2), math.sin(th + vel[2] * h / 2)
        x, y, th = x + (c * vel[0] - s * vel[1]) * h, y + (s * vel[0] + c * vel[1]) * h, th + vel[2] * h
    return x, y, th


@pytest.mark.parametrize("vel", [(0.5, 0.0, 0.0), (0.0, -0.4, 0.0), (0.3, 0.2, 1.5), (-0.2, 0.4, -1.9)])
def test_predict_pose_follows_the_body_twist(vel):
    start = (1.0, 2.0, 0.7)
    got = predict_pose(start, vel, 0.3)
    want = _euler(start, vel, 0.3)
    assert got[:2] == pytest.approx(want[:2], abs=1e-6)
    assert math.remainder(got[2] - want[2], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert predict_pose(start, vel, 0.0) == start


def test_mean_twist_ramps_toward_the_last_command():
    # vx 0 -> 0.5 at 1.5 m/s^2 takes 1/3 s: over 0.2 s still ramping (mean 0.15); over 0.5 s ramp then hold
    assert mean_twist((0.0, 0.0, 0.0), (0.5, 0.0, 0.0), ACC, 0.2)[0] == pytest.approx(0.15)
    ramp = 0.5 / 1.5
    assert mean_twist((0.0, 0.0, 0.0), (0.5, 0.0, 0.0), ACC, 0.5)[0] == pytest.approx(
        (0.25 * ramp + 0.5 * (0.5 - ramp)) / 0.5)
    # braking and turning: each axis on its own limit
    vx, vy, wz = mean_twist((0.5, -0.2, 1.0), (0.0, -0.2, -1.0), ACC, 0.1)
    assert (vx, vy, wz) == pytest.approx((0.5 - 0.075, -0.2, 1.0 - 0.15))


def test_latency_estimate_is_pose_age_plus_a_high_tick_quantile():
    est = LatencyEstimate(window=10, quantile=0.9)
    assert est.expected(0.02) == pytest.approx(0.02)
    for d in (0.01, 0.01, 0.02, 0.02, 0.02, 0.03, 0.03, 0.03, 0.04, 0.12):
        est.add_tick(d)
    assert est.expected(0.02) == pytest.approx(0.02 + 0.12)
    est.add_tick(float("nan"))
    est.add_tick(0.01)            # the window drops the oldest
    assert est.tick_quantile() == pytest.approx(0.12)
    assert est.expected(float("inf")) == pytest.approx(0.12)


def _costmap(grid):
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    return cm


@pytest.mark.parametrize("kind", ["pursuit", "mppi"])
def test_command_is_the_one_for_the_acting_pose(kind):
    """With a latency set, a step equals the step of an uncompensated controller placed at the acting pose."""
    grid, start, goal = CORRIDOR
    cm = _costmap(grid)
    path = GlobalPlanner().plan(cm, start[:2], goal[:2]).path

    def make(comp):
        cfg = ControllerConfig(footprint=FP, latency_compensation=comp)
        ctl = MppiController(cfg, MppiConfig(seed=3)) if kind == "mppi" else HolonomicController(cfg)
        ctl.set_path(path)
        return ctl

    pose, vel, last = (2.0, 1.1, 0.1), (0.4, 0.05, 0.3), (0.5, 0.0, 0.0)
    a, b = make(True), make(False)
    a.set_latency(0.2, last)
    acting = a.acting_pose(pose, vel)
    assert acting == pytest.approx(predict_pose(pose, mean_twist(vel, last, ACC, 0.2), 0.2))
    assert math.hypot(acting[0] - pose[0], acting[1] - pose[1]) > 0.08
    out_a = a.compute(pose, vel, goal, cm, 0.05)
    out_b = b.compute(acting, vel, goal, cm, 0.05)
    assert (out_a.vx, out_a.vy, out_a.wz) == pytest.approx((out_b.vx, out_b.vy, out_b.wz))


def test_latency_is_capped_and_can_be_switched_off():
    ctl = HolonomicController(ControllerConfig(footprint=FP, max_latency=0.25))
    ctl.set_latency(0.9)
    assert ctl.latency == 0.25
    assert ctl.measured_latency == 0.9
    ctl.set_latency(float("nan"))
    assert ctl.latency == 0.0
    off = HolonomicController(ControllerConfig(footprint=FP, latency_compensation=False))
    off.set_latency(0.2)
    assert off.acting_pose((1.0, 1.0, 0.0), (0.5, 0.0, 0.0)) == (1.0, 1.0, 0.0)


def _delayed_loop(ctl, grid, start, goal, delay, t_max=90.0, dt=0.05, sub=10):
    """(reached, contact sub-steps): ticks every dt; the pose read is delay/2 old, the command acts delay/2
    after the tick; the base tracks the acting command at the acceleration limits."""
    cm = _costmap(grid)
    ctl.set_path(GlobalPlanner().plan(cm, start[:2], goal[:2]).path)
    gc = GoalChecker()
    pose, vel, acting, last = start, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    seen = collections.deque()       # (t, pose, vel): what a stale read returns
    pending = collections.deque()    # (t it acts, command)
    t, h, contacts = 0.0, dt / sub, 0
    while t < t_max:
        seen.append((t, pose, vel))
        while len(seen) > 1 and seen[1][0] <= t - delay / 2 + 1e-9:
            seen.popleft()
        _, p_read, v_read = seen[0]
        if gc.is_goal_reached(pose, goal):
            return True, contacts
        ctl.set_latency(delay, last)
        out = ctl.compute(p_read, v_read, goal, cm, dt, gc.xy_reached(p_read, goal))
        last = (out.vx, out.vy, out.wz)
        pending.append((t + delay / 2, last))
        for _ in range(sub):
            while pending and pending[0][0] <= t + 1e-9:
                acting = pending.popleft()[1]
            vel = tuple(float(np.clip(u, v - a * h, v + a * h)) for u, v, a in zip(acting, vel, ACC, strict=True))
            c, s = math.cos(pose[2]), math.sin(pose[2])
            pose = (pose[0] + (c * vel[0] - s * vel[1]) * h, pose[1] + (s * vel[0] + c * vel[1]) * h,
                    pose[2] + vel[2] * h)
            t += h
            contacts += footprint_collides(grid, pose)
    return False, contacts


def test_late_commands_touch_the_corridor_without_compensation_and_not_with_it():
    grid, start, goal = CORRIDOR
    reached, contacts = _delayed_loop(HolonomicController(ControllerConfig(footprint=FP, latency_compensation=False)),
                                      grid, start, goal, delay=0.3)
    assert contacts > 0          # the failure this guards against is real in this loop
    reached, contacts = _delayed_loop(HolonomicController(ControllerConfig(footprint=FP)), grid, start, goal,
                                      delay=0.3)
    assert reached
    assert contacts == 0


def test_mppi_with_late_commands_reaches_the_goal_without_contact():
    grid, start, goal = CORRIDOR
    reached, contacts = _delayed_loop(MppiController(ControllerConfig(footprint=FP), MppiConfig(seed=1)), grid, start,
                                      goal, delay=0.25)
    assert reached
    assert contacts == 0


@pytest.mark.parametrize("kind", ["pursuit", "mppi"])
def test_a_long_latency_slows_the_base_to_the_blind_travel_budget(kind):
    """At 1 s of latency and a 0.15 m budget the base may go 0.15 m/s; at 0.2 s the full 0.5 m/s."""
    grid, start, goal = CORRIDOR
    cm = _costmap(grid)
    path = GlobalPlanner().plan(cm, start[:2], goal[:2]).path
    speeds = {}
    for latency in (0.2, 1.0):
        cfg = ControllerConfig(footprint=FP, max_blind_travel=0.15)
        ctl = MppiController(cfg, MppiConfig(seed=2)) if kind == "mppi" else HolonomicController(cfg)
        ctl.set_path(path)
        pose, vel = (1.5, 1.0, 0.0), (0.0, 0.0, 0.0)
        top = 0.0
        for _ in range(40):         # accelerate along the open start of the corridor
            ctl.set_latency(latency, vel)
            out = ctl.compute(pose, vel, goal, cm, 0.05)
            vel = (out.vx, out.vy, out.wz)
            pose = predict_pose(pose, vel, 0.05)
            top = max(top, math.hypot(out.vx, out.vy))
        speeds[latency] = top
        assert ctl.speed_limit == 1.0       # the cut applies inside a step, not to the limit set from outside
    assert speeds[1.0] <= 0.15 + 1e-6
    assert speeds[0.2] > 0.3


def test_the_latency_speed_cut_stops_at_the_regulation_floor():
    ctl = HolonomicController(ControllerConfig(footprint=FP, max_blind_travel=0.15,
                                               regulated_linear_scaling_min_speed=0.15))
    for latency, fraction in ((0.1, 1.0), (0.3, 1.0), (0.4, 0.75), (1.0, 0.3), (5.0, 0.3)):
        ctl.set_latency(latency)
        assert ctl.latency_speed_fraction() == pytest.approx(fraction)
