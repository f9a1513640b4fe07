"""Escape recovery (footprint clearance to lethal cells and scan points) and the blocked/slow progress checker."""

import math

import numpy as np

from nav2_wrapper.core import escape as esc
from nav2_wrapper.core.checkers import BLOCKED, OK, SLOW, STUCK, ProgressChecker, ProgressCheckerConfig
from nav2_wrapper.core.controller import ControllerConfig, HolonomicController
from nav2_wrapper.core.costmap import Costmap, CostmapConfig
from nav2_wrapper.core.recoveries import Escape, RecoveryConfig, RecoverySequence
from nav2_wrapper.robot_io import load_footprint

from .sim import footprint_collides, room

FP = load_footprint()
POLY = FP.polygon


def _drive(beh, pose, cm, ctrl, dt=0.05, steps=600):
    """Integrate the behaviour's body-frame commands until it is done; returns (last step, final pose, poses)."""
    x, y, th = pose
    seen = []
    for k in range(steps):
        s = beh.step(k * dt, (x, y, th), cm, ctrl)
        if s.done:
            return s, (x, y, th), seen
        c, sn = math.cos(th), math.sin(th)
        x += (c * s.vx - sn * s.vy) * dt
        y += (sn * s.vx + c * s.vy) * dt
        th += s.wz * dt
        seen.append((x, y, th))
    raise AssertionError("behaviour never finished")


def test_clearance_is_signed_distance_from_the_polygon() -> None:
    hx, hy = float(POLY[:, 0].max()), float(POLY[:, 1].max())
    obs = esc.Obstacles(np.array([[hx + 0.10, 0.0], [0.0, hy + 0.30], [0.0, 0.0]]), np.zeros(3))
    outside = esc.Obstacles(obs.points[:2], np.array([0.0, 0.02]))
    assert abs(esc.clearance(POLY, np.array([[0.0, 0.0, 0.0]]), outside)[0] - 0.10) < 1e-9
    inside = esc.clearance(POLY, np.array([[0.0, 0.0, 0.0]]), obs)[0]
    assert abs(inside + min(hx, hy)) < 1e-9                               # the centre point: negative, by the inradius
    turned = esc.clearance(POLY, np.array([[0.0, 0.0, math.pi / 2]]), esc.Obstacles(obs.points[:1], obs.radii[:1]))
    assert abs(turned[0] - (hx + 0.10 - hy)) < 1e-9                       # the short side now faces the point


def _wedged():
    """Posts behind (3 cm) and on both long sides (5 cm) of a base facing +x; only forward (+x) is open."""
    hx = float(POLY[:, 0].max())
    e = 1e-3                                                               # keep cell rounding off the faces
    grid = room(6, 6, boxes=((2.50 + e, 2.60 + e, 2.60 - e, 3.40 - e),     # behind: face at x = 2.60
                             (2.80 + e, 2.60 + e, 3.30 - e, 2.70 - e),     # right side: face at y = 2.70
                             (2.80 + e, 3.30 + e, 3.30 - e, 3.40 - e)))    # left side: face at y = 3.30
    pose = (2.60 + 0.03 + hx, 3.0, 0.0)
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    return grid, pose, cm


def test_wedged_on_three_sides_escapes_forward_not_backward() -> None:
    grid, pose, cm = _wedged()
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    assert not footprint_collides(grid, pose)
    obs = esc.gather_obstacles(cm, pose[0], pose[1], 1.2)
    c0 = esc.clearance(POLY, np.array([pose]), obs)[0]
    assert 0.02 <= c0 <= 0.04, c0
    back = esc.Motion(-0.15, 0.0, 0.0)                                   # body-backwards: into the post
    assert esc.clearance(POLY, back.poses(pose, 15), obs).min() < 0.0

    beh = Escape(RecoveryConfig(), lambda: None)
    beh.start(0.0, pose)
    s, end, seen = _drive(beh, pose, cm, ctrl)
    assert s.ok, s.detail
    assert "escaped" in s.detail
    assert "clearance" in s.detail
    assert end[0] - pose[0] > 0.10, end                                  # went forward, the only open way
    assert abs(end[1] - pose[1]) < 0.03, end
    assert all(not footprint_collides(grid, p) for p in seen)
    c1 = esc.clearance(POLY, np.array([end]), esc.gather_obstacles(cm, end[0], end[1], 1.2))[0]
    assert c1 > c0 + 0.015, (c0, c1)


def test_escape_tie_breaks_toward_the_path() -> None:
    """In the open every motion reaches enough clearance; the one along the path (here +y) wins."""
    grid = room(6, 6)
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FP))
    cm.set_static_map(grid)
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    ctrl.set_path(np.array([[3.0, 3.0 + 0.1 * k] for k in range(20)]))
    beh = Escape(RecoveryConfig(), lambda: None)
    beh.start(0.0, (3.0, 3.0, 0.0))
    s = beh.step(0.0, (3.0, 3.0, 0.0), cm, ctrl)
    assert not s.done
    assert s.vy > 0.05, (s.vx, s.vy)                                   # body y = world y at yaw 0
    assert abs(s.vx) < 0.02, (s.vx, s.vy)


def test_no_free_motion_is_reported_with_scan_points() -> None:
    """Boxed in on every side 2 cm away, seen only by the scan: every sampled motion closes a gap."""
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FP))
    cm.set_static_map(room(6, 6))
    ctrl = HolonomicController(ControllerConfig(footprint=FP))
    hx, hy = float(POLY[:, 0].max()) + 0.02, float(POLY[:, 1].max()) + 0.02
    t = np.linspace(-1.0, 1.0, 60)
    ring = np.vstack([np.c_[hx * t, np.full_like(t, hy)], np.c_[hx * t, np.full_like(t, -hy)],
                      np.c_[np.full_like(t, hx), hy * t], np.c_[np.full_like(t, -hx), hy * t]])
    pose = (3.0, 3.0, 0.0)
    pts = ring + np.array(pose[:2])
    seq = RecoverySequence(RecoveryConfig(behaviors=("escape", "spin")), lambda: None, lambda: pts)
    beh = seq.begin(0.0, pose)
    assert beh is not None
    assert beh.name == "escape"
    s = seq.step(0.0, pose, cm, ctrl)
    assert s.done
    assert not s.ok
    assert "none of" in s.detail, s.detail
    assert "collision-free" in s.detail, s.detail
    assert (s.vx, s.vy, s.wz) == (0.0, 0.0, 0.0)
    again = seq.begin(0.1, pose, prefer="escape")                      # it just failed: try something else
    assert again is not None
    assert again.name == "spin"
    # without the scan points the same spot is open: the refusal came from them
    free = RecoverySequence(RecoveryConfig(behaviors=("escape",)), lambda: None)
    free.begin(0.0, pose)
    assert not free.step(0.0, pose, cm, ctrl).done


def test_prefer_runs_the_named_behaviour_and_keeps_the_round_robin() -> None:
    seq = RecoverySequence(RecoveryConfig(behaviors=("clear_costmaps", "spin", "escape")), lambda: None)
    assert seq.begin(0.0, (0, 0, 0), prefer="escape").name == "escape"
    seq.active = None
    assert seq.begin(0.0, (0, 0, 0)).name == "clear_costmaps"
    assert seq.used == 2


# ---- progress checker: blocked vs slow --------------------------------------------------------------------

def _run_checker(pc, dt, n, pose_at, **kw):
    out = []
    for k in range(n + 1):
        t = k * dt
        out.append((t, pc.assess(t, pose_at(t), **{a: (f(t) if callable(f) else f) for a, f in kw.items()})))
    return out


def test_slow_robot_gets_a_bounded_extension_not_a_recovery() -> None:
    cfg = ProgressCheckerConfig()
    pc = ProgressChecker(cfg)
    v = 0.04                                                        # above blocked_speed, below 0.5 m / 10 s
    res = _run_checker(pc, 0.1, 130, lambda t: (v * t, 0.0, 0.0), command=v, remaining=lambda t: 5.0 - v * t)
    states = {s.state for t, s in res}
    assert STUCK not in states
    assert BLOCKED not in states
    slow = [(t, s) for t, s in res if s.state == SLOW]
    assert slow
    assert slow[0][0] > cfg.movement_time_allowance, slow[:1]
    assert "slow" in slow[0][1].detail
    assert "along the path" in slow[0][1].detail
    assert res[-1][1].state == OK                                   # left the radius at 12.5 s: fresh window


def test_slow_extension_is_bounded() -> None:
    cfg = ProgressCheckerConfig(required_movement_radius=1.5)
    pc = ProgressChecker(cfg)
    v = 0.04
    res = _run_checker(pc, 0.1, 300, lambda t: (v * t, 0.0, 0.0), command=v, remaining=lambda t: 5.0 - v * t)
    first_stuck = next(t for t, s in res if s.state == STUCK)
    assert abs(first_stuck - (cfg.movement_time_allowance + cfg.slow_extension_max)) < 0.15


def test_moving_without_path_progress_is_not_slow() -> None:
    """Circling in place (moving, but the remaining path does not shrink) is stuck at the plain allowance."""
    pc = ProgressChecker()
    res = _run_checker(pc, 0.1, 120, lambda t: (0.1 * math.cos(t * 0.4), 0.1 * math.sin(t * 0.4), 0.0),
                       command=0.04, remaining=5.0)
    first_stuck = next(t for t, s in res if s.state == STUCK)
    assert 10.0 < first_stuck < 10.3


def test_command_not_realised_is_blocked_early() -> None:
    cfg = ProgressCheckerConfig()
    pc = ProgressChecker(cfg)
    res = _run_checker(pc, 0.1, 100, lambda t: (1.0, 1.0, 0.0), command=0.3, remaining=5.0)
    first = next((t, s) for t, s in res if not s.ok)
    assert first[1].state == BLOCKED
    assert "commanded 0.30 m/s" in first[1].detail
    assert first[0] < cfg.movement_time_allowance / 2
    assert first[0] >= cfg.blocked_time_allowance


def test_pressed_against_an_obstacle_is_blocked_even_with_no_command() -> None:
    pc = ProgressChecker()
    res = _run_checker(pc, 0.1, 100, lambda t: (1.0, 1.0, 0.0), command=0.0, remaining=5.0, pressed=True)
    first = next((t, s) for t, s in res if not s.ok)
    assert first[1].state == BLOCKED
    assert "pressed" in first[1].detail


def test_standing_still_unpressed_uncommanded_is_plain_stuck() -> None:
    pc = ProgressChecker()
    res = _run_checker(pc, 0.1, 110, lambda t: (1.0, 1.0, 0.0), command=0.0, remaining=5.0)
    first = next((t, s) for t, s in res if not s.ok)
    assert first[1].state == STUCK
    assert "no progress" in first[1].detail
    assert 10.0 < first[0] < 10.3


def test_blocked_toward_detects_pressing_into_a_post() -> None:
    _, pose, cm = _wedged()
    obs = esc.gather_obstacles(cm, pose[0], pose[1], 1.2)
    assert esc.blocked_toward(POLY, pose, obs, (-1.0, 0.0), margin=0.05)      # toward the post behind
    assert not esc.blocked_toward(POLY, pose, obs, (1.0, 0.0), margin=0.05)   # away from it


def test_navigator_escapes_a_stalled_base_well_before_the_plain_allowance() -> None:
    """The base does not move whatever it is told (a wheel against a post the map does not show): the
    progress checker calls it blocked after blocked_time_allowance and the escape starts, instead of the
    robot sitting out movement_time_allowance."""
    from nav2_wrapper.core import Navigator
    from nav2_wrapper.params import load_params

    n = Navigator(load_params("sim").config)
    pose = (1.5, 1.5, 0.0)
    n.tick(0.0, pose, grid=room(6, 6))
    n.navigate(4.5, 4.5, 0.0, 0.0)
    t, cmd = 0.0, None
    while t < 8.0:
        t += 0.05
        cmd = n.tick(t, pose)
        if "recovering" in cmd.detail:
            break
    assert cmd is not None
    assert "recovering: escape after: blocked: commanded" in cmd.detail, cmd.detail
    pc = n.cfg.progress_checker
    assert t < pc.movement_time_allowance / 2
    assert n.recovery.history == ["escape"]
