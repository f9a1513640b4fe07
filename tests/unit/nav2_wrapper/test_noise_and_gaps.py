"""Noisy lidar (range noise + dropouts) and tight gaps: the cases that used to end in "controller found no
collision-free command". Closed loop with the kinematic integrator; seeded noise, so deterministic."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nav2_wrapper.core import Costmap, CostmapConfig, Navigator, Scan
from nav2_wrapper.core.costs import LETHAL
from nav2_wrapper.params import load_params

from .sim import FOOTPRINT, cast_scan, drive, room


def noisy(std: float, dropout: float, seed: int = 0):
    """A scan function like the sim's lidar: Gaussian range noise on returns, dropouts reported as +inf."""
    rng = np.random.default_rng(seed)

    def scan(grid, pose):  # type: ignore[no-untyped-def]
        s = cast_scan(grid, pose)
        r = s.ranges.copy()
        hit = np.isfinite(r)
        r[hit] += rng.normal(0.0, std, int(hit.sum()))
        r[rng.random(len(r)) < dropout] = np.inf
        return Scan(r, s.angle_min, s.angle_increment, s.range_min, s.range_max)

    return scan


# A piece of the apartment: the kitchen → bedroom_2 doorway (1.1 m clear below the wall line, 0.9 m between the
# door post and the bathroom wall that starts at the door), entered from the south-west and left to the north-west.
DOORWAY = room(10, 8, boxes=((0, 4.95, 8.05, 5.05), (9.15, 4.95, 10, 5.05), (8.95, 4.95, 9.05, 8)))


@pytest.mark.parametrize(("std", "dropout", "seed"), [(0.02, 0.02, 0), (0.03, 0.05, 0), (0.03, 0.05, 1)])
def test_noisy_lidar_through_a_doorway(std: float, dropout: float, seed: int) -> None:
    n = Navigator(load_params("sim").config)
    n.navigate(7.0, 6.5, 0.0, 0.0)
    run = drive(n, DOORWAY, (7.0, 1.5, 0.0), 90.0, scan_fn=noisy(std, dropout, seed))
    assert run.cmds[-1].state == "SUCCEEDED", run.cmds[-1].detail
    assert not run.collided
    assert n.active is not None
    assert n.active.recoveries == 0


def corridor_with_box(gap: float) -> tuple:
    """A 1.9 m corridor (like the office one) with a box leaving ``gap`` m clear on its north side."""
    lo, hi = 1.0, 2.9
    return room(12, 4, boxes=((0, 0, 12, lo), (0, hi, 12, 4), (5.7, lo, 6.3, hi - gap))), (lo + hi) / 2


@pytest.mark.parametrize("scan", ["clean", "noisy"])
@pytest.mark.parametrize("known", [True, False], ids=["box_in_map", "box_seen_by_lidar_only"])
def test_passes_a_gap_wider_than_the_footprint_width(scan: str, known: bool) -> None:
    world, mid = corridor_with_box(0.8)
    n = Navigator(load_params("sim").config)
    n.navigate(10.5, mid, 0.0, 0.0)
    grid = world if known else corridor_with_box(1.9)[0]
    run = drive(n, grid, (1.0, mid, 0.0), 90.0, world=world, scan_fn=noisy(0.02, 0.02) if scan == "noisy" else None)
    assert run.cmds[-1].state == "SUCCEEDED", run.cmds[-1].detail
    assert not run.collided


def test_dropout_never_clears_and_too_close_is_not_free() -> None:
    """inf_is_valid clears +inf beams to the raytrace range; -inf (closer than range_min) never clears."""
    cfg = CostmapConfig(static_layer=False, width=6.0, height=6.0, track_unknown_space=False, footprint=FOOTPRINT)
    cfg.observation_sources[0].inf_is_valid = True
    cm = Costmap(cfg)
    cm.obstacle[60, 70] = LETHAL     # a mark 0.5 m east of the sensor at (3.0, 3.0)
    cm.obstacle[60, 50] = LETHAL     # and one 0.5 m west
    ranges = np.array([np.inf, -np.inf])  # beam 0 east (dropout), beam 1 west (too close)
    cm.update_scan(Scan(ranges, 0.0, math.pi, 0.05, 12.0), (3.025, 3.025, 0.0))
    assert cm.obstacle[60, 70] != LETHAL
    assert cm.obstacle[60, 50] == LETHAL


def test_controller_lines_up_with_a_gap_entered_diagonally() -> None:
    """A 0.75 m slot in a thin wall, approached and left at 45°: the body must line up with the slot, and the
    turn out of it must not clip the wall end between two collision samples (it once did, in 0.05 s)."""
    from nav2_wrapper.core import ControllerConfig, GlobalPlanner, GoalChecker, HolonomicController

    from .sim import footprint_collides

    grid = room(9, 7, boxes=((4.0, 0, 4.1, 3.0), (4.0, 3.8, 4.1, 7)))   # rasterised: 0.75 m clear
    cm = Costmap(CostmapConfig(obstacle_layer=False, cost_scaling_factor=3.0, footprint=FOOTPRINT))
    cm.set_static_map(grid)
    start, goal = (2.0, 1.0, 0.8), (6.8, 5.8, 0.0)
    plan = GlobalPlanner().plan(cm, start[:2], goal[:2])
    assert plan.ok, plan.reason
    ctrl = HolonomicController(ControllerConfig(footprint=FOOTPRINT))
    ctrl.set_path(plan.path)
    gc = GoalChecker()
    (x, y, th), vel, dt, blocked = start, (0.0, 0.0, 0.0), 0.05, 0
    for _ in range(1500):
        if gc.is_goal_reached((x, y, th), goal):
            break
        out = ctrl.compute((x, y, th), vel, goal, cm, dt, gc.xy_reached((x, y, th), goal))
        blocked += out.blocked
        c, s = math.cos(th), math.sin(th)
        x, y, th = x + (c * out.vx - s * out.vy) * dt, y + (s * out.vx + c * out.vy) * dt, th + out.wz * dt
        vel = (out.vx, out.vy, out.wz)
        assert not footprint_collides(grid, (x, y, th)), (x, y, th)
    assert gc.is_goal_reached((x, y, th), goal), ((x, y, th), blocked)
    assert blocked == 0


def test_backup_moves_away_from_a_wall_it_touches_not_into_it() -> None:
    """Body-backwards points into the wall here (yaw -90°: back = +y, the wall is at +y); a holonomic
    backup must pick a direction that leaves the contact instead of refusing or pushing into it."""
    import numpy as np

    from nav2_wrapper.core.controller import ControllerConfig, HolonomicController
    from nav2_wrapper.core.costmap import Costmap, CostmapConfig
    from nav2_wrapper.core.recoveries import BackUp, RecoveryConfig
    from robonix_common.grid import GridMap

    data = np.zeros((80, 80), np.int8)
    data[50:52, :] = 100                     # a wall along y = 2.5 .. 2.6 m
    cm = Costmap(CostmapConfig(footprint=FOOTPRINT))
    cm.set_static_map(GridMap(data, 0.05))
    ctl = HolonomicController(ControllerConfig(footprint=FOOTPRINT))
    pose = (2.0, 2.5 - 0.36, -np.pi / 2)    # the long side's end touches the wall; body-back = +y
    b = BackUp(RecoveryConfig())
    b.start(0.0, pose)
    step = b.step(0.0, pose, cm, ctl)
    assert not step.done, step.detail
    c, s = np.cos(pose[2]), np.sin(pose[2])
    world_vy = s * step.vx + c * step.vy
    assert world_vy < -1e-3, (step.vx, step.vy)   # away from the wall (−y), never into it
