"""Pause / grace / fail of a running goal while a required input is lost (core/grace.py + Navigator.pause)."""

import math

import pytest

from nav2_wrapper.core import Navigator
from nav2_wrapper.core.grace import FAILED, OK, PAUSED, InputGrace
from nav2_wrapper.params import ParamsError, load_params
from robonix_nav_data import resources

from .sim import drive, room

WORLD = room(10, 8, boxes=((3, 0, 3.5, 5), (6.5, 3, 7, 8)))
LOST = {"mapping": "TF map→odom stopped (DDS liveliness lost)"}


def test_grace_pauses_then_resumes_when_the_input_returns():
    g = InputGrace(5.0)
    assert g.update(0.0, 100.0, {}) == g.update(0.1, 100.1, {})  # nothing lost: OK, no resume
    v = g.update(1.0, 101.0, LOST)
    assert v.state == PAUSED
    assert v.detail.startswith("waiting for mapping (TF map→odom")
    assert "fails in 5.0 s" in v.detail
    assert g.paused
    v = g.update(4.0, 104.0, LOST)
    assert v.state == PAUSED
    assert "fails in 2.0 s" in v.detail
    v = g.update(4.5, 104.5, {})
    assert v.state == OK
    assert v.resumed
    assert not g.paused
    assert not g.update(4.6, 104.6, {}).resumed


def test_grace_fails_naming_the_input_after_the_grace_on_both_clocks():
    g = InputGrace(5.0)
    g.update(0.0, 0.0, LOST)
    # sim time ran 3x faster than wall: 6 s sim is only 2 s wall, so the grace is not over
    assert g.update(6.0, 2.0, LOST).state == PAUSED
    v = g.update(15.1, 5.1, LOST)
    assert v.state == FAILED
    assert v.detail == ("mapping lost: TF map→odom stopped (DDS liveliness lost) "
                        "(not back within input_grace_s=5 s)")


def test_grace_counts_each_input_from_its_own_loss():
    g = InputGrace(2.0)
    g.update(0.0, 0.0, {"mapping": "a"})
    v = g.update(1.5, 1.5, {"mapping": "a", "panda_mobile": "b"})
    assert v.state == PAUSED
    assert v.detail.startswith("waiting for mapping, panda_mobile (mapping: a; panda_mobile: b)")
    v = g.update(2.5, 2.5, {"panda_mobile": "b"})       # mapping back; panda_mobile only 1 s lost
    assert v.state == PAUSED
    assert g.update(3.6, 3.6, {"panda_mobile": "b"}).detail.startswith("panda_mobile lost: b")


def test_navigator_pause_holds_the_goal_and_resume_finishes_it():
    n = Navigator(load_params("sim").config)
    rec = n.navigate(9.0, 1.0, math.pi / 2, 0.0)
    run = drive(n, WORLD, (1.0, 1.0, 0.0), 4.0)
    assert run.cmds[-1].state == "RUNNING"
    assert math.hypot(run.cmds[-1].vx, run.cmds[-1].vy) > 0.05
    pose = run.poses[-1]
    n.pause("waiting for mapping (test)")
    # paused for 12 s of sim time: longer than the progress checker's window, and every command is zero
    for k in range(240):
        cmd = n.tick(run.t + k * 0.05, pose)
        assert (cmd.vx, cmd.vy, cmd.wz) == (0.0, 0.0, 0.0)
        assert cmd.state == "RUNNING"
        assert cmd.detail == "waiting for mapping (test)"
    assert rec.state == "RUNNING"
    assert n.paused
    n.resume()
    rest = drive(n, WORLD, pose, 120.0, t0=run.t + 12.0)
    assert rest.cmds[-1].state == "SUCCEEDED", rest.cmds[-1].detail
    assert rec.recoveries == 0          # standing still while paused did not count as "no progress"
    assert not rest.collided


def test_navigator_pause_is_cleared_by_a_new_goal_and_ignored_when_idle():
    n = Navigator(load_params("sim").config)
    n.pause("waiting for x")             # no goal: nothing to hold
    assert not n.paused
    n.navigate(9.0, 1.0, 0.0, 0.0)
    n.pause("waiting for x")
    assert n.paused
    n.navigate(9.0, 2.0, 0.0, 0.1)       # preempts: the new goal starts unpaused
    assert not n.paused


def test_input_grace_param_is_read_and_validated(tmp_path):
    assert load_params("sim").config.navigator.input_grace_s == 5.0
    src = (resources.data_root() / "config" / "nav2_params_sim.yml").read_text()
    bad = tmp_path / "p.yml"
    bad.write_text(src.replace("input_grace_s: 5.0", "input_grace_s: -1"))
    with pytest.raises(ParamsError, match="input_grace_s"):
        load_params(bad)
    good = tmp_path / "g.yml"
    good.write_text(src.replace("input_grace_s: 5.0", "input_grace_s: 12"))
    assert load_params(good).config.navigator.input_grace_s == 12.0
