"""Navigator end to end in a closed loop with a kinematic integrator (no MuJoCo, no DDS)."""

import math

import numpy as np
import pytest

from nav2_wrapper.core import Navigator
from nav2_wrapper.params import load_params

from .sim import add_box, drive, room


def nav():
    return Navigator(load_params("sim").config)


WORLD = room(10, 8, boxes=((3, 0, 3.5, 5), (6.5, 3, 7, 8)))


def test_reaches_goal_without_collision():
    n = nav()
    rec = n.navigate(9.0, 1.0, math.pi / 2, 0.0)
    assert rec.accepted
    assert rec.state == "PENDING"
    run = drive(n, WORLD, (1.0, 1.0, 0.0), 120.0)
    assert run.cmds[-1].state == "SUCCEEDED", run.cmds[-1].detail
    assert not run.collided
    x, y, th = run.poses[-1]
    assert math.hypot(x - 9.0, y - 1.0) <= 0.25 + 0.02
    assert abs(th - math.pi / 2) <= 0.25 + 0.05
    running = [c.detail for c in run.cmds if c.state == "RUNNING"]
    assert "m remaining, ETA" in running[len(running) // 2]
    assert n.tick(run.t, run.poses[-1]).vx == 0.0


def test_unreachable_goal_fails_with_reason():
    world = room(10, 8, boxes=((6, 2, 6.2, 6), (6, 2, 9, 2.2), (6, 5.8, 9, 6), (8.8, 2, 9, 6)))
    n = nav()
    n.navigate(7.5, 4.0, 0.0, 0.0)
    run = drive(n, world, (1.0, 1.0, 0.0), 10.0)
    assert run.cmds[-1].state == "FAILED"
    assert "no path" in run.cmds[-1].detail
    assert (run.cmds[-1].vx, run.cmds[-1].vy, run.cmds[-1].wz) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize(("goal", "why"), [((3.2, 2.0), "inside an obstacle"), ((30.0, 2.0), "off the map"),
                                        ((float("nan"), 2.0), "non-finite")])
def test_invalid_goals_are_rejected(goal, why):
    n = nav()
    n.tick(0.0, (1.0, 1.0, 0.0), grid=WORLD)
    rec = n.navigate(goal[0], goal[1], 0.0, 0.1)
    assert not rec.accepted
    assert rec.state == "FAILED"
    assert why in rec.detail
    assert n.status(rec.run_id) is rec


def test_cancel_stops_with_zero_command():
    n = nav()
    rec = n.navigate(9.0, 1.0, 0.0, 0.0)
    run = drive(n, WORLD, (1.0, 1.0, 0.0), 3.0)
    assert run.cmds[-1].state == "RUNNING"
    assert math.hypot(run.cmds[-1].vx, run.cmds[-1].vy) > 0.05
    n.cancel(3.0)
    cmd = n.tick(3.05, run.poses[-1], (0.3, 0.0, 0.0))
    assert (cmd.vx, cmd.vy, cmd.wz) == (0.0, 0.0, 0.0)
    assert cmd.state == "CANCELED"
    assert n.status(rec.run_id).state == "CANCELED"


def test_preempt_cancels_old_goal():
    n = nav()
    old = n.navigate(9.0, 1.0, 0.0, 0.0)
    run = drive(n, WORLD, (1.0, 1.0, 0.0), 2.0)
    new = n.navigate(1.5, 6.0, 0.0, 2.0)
    assert old.state == "CANCELED"
    assert "preempted" in old.detail
    run2 = drive(n, WORLD, run.poses[-1], 60.0, t0=2.0)
    assert run2.cmds[-1].state == "SUCCEEDED"
    assert run2.cmds[-1].run_id == new.run_id
    assert not run2.collided


def test_replans_around_a_new_obstacle():
    known = room(10, 6)
    world_later = add_box(known, (4.6, 0.0, 5.4, 4.0))       # dropped into the straight path
    n = nav()
    n.navigate(8.5, 1.5, 0.0, 0.0)
    first_path = []

    def remember(t, run):
        if not first_path:
            first_path.append(n.path.copy())

    # the box appears after 1 s: the second leg ray-casts on the changed world, the map stays stale
    run1 = drive(n, known, (1.0, 1.5, 0.0), 1.0, on_step=remember)
    run2 = drive(n, known, run1.poses[-1], 90.0, t0=run1.t, world=world_later)
    assert np.max(first_path[0][:, 1]) < 2.0                  # planned straight at first
    assert run2.cmds[-1].state == "SUCCEEDED", run2.cmds[-1].detail
    assert not run2.collided
    ys = np.array(run2.poses)[:, 1]
    assert ys.max() > 4.0                                      # went around the box's end
