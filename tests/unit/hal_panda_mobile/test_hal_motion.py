"""Velocity control and odometry of the simulated base."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal_panda_mobile.sim import OdomNoise
from robonix_common.geometry import wrap_angle

from .conftest import drive, make_sim, room

BIG = room(10.0, 10.0)  # "empty": walls far beyond a 1 m square


def _assert_odom_equals_gt(sim) -> None:
    gt, od = sim.ground_truth(), sim.odometry()
    assert abs(od.x - gt[0]) < 1e-6
    assert abs(od.y - gt[1]) < 1e-6
    assert abs(wrap_angle(od.yaw - gt[2])) < 1e-6
    assert np.allclose((od.vx, od.vy, od.wz), gt[3:], atol=1e-6)


def test_square_forward_and_turn_matches_command_and_odometry(robot):
    """4 x (1 m forward at 0.4 m/s, settle, 90 deg turn, settle): the accel ramps are symmetric, so each
    corner must be within 1 cm / 0.01 rad of the commanded square; noise-free odom equals ground truth."""
    sim = make_sim(robot, BIG)
    expected = [(1.0, 0.0, math.pi / 2), (1.0, 1.0, math.pi), (0.0, 1.0, -math.pi / 2), (0.0, 0.0, 0.0)]
    for ex, ey, eyaw in expected:
        drive(sim, 0.4, 0.0, 0.0, 2.5)
        drive(sim, 0.0, 0.0, 0.0, 0.5)
        _assert_odom_equals_gt(sim)
        drive(sim, 0.0, 0.0, (math.pi / 2) / 1.5, 1.5)
        drive(sim, 0.0, 0.0, 0.0, 0.5)
        x, y, yaw = sim.ground_truth()[:3]
        assert math.hypot(x - ex, y - ey) < 0.01, (x, y, ex, ey)
        assert abs(wrap_angle(yaw - eyaw)) < 0.01
        _assert_odom_equals_gt(sim)
    assert sim.collisions() == []


def test_holonomic_strafe_square_keeps_heading(robot):
    sim = make_sim(robot, {**BIG, "start": [0.5, -0.5, 0.7]})
    for vx, vy in ((0.3, 0.0), (0.0, 0.3), (-0.3, 0.0), (0.0, -0.3)):
        drive(sim, vx, vy, 0.0, 3.0)
        drive(sim, 0.0, 0.0, 0.0, 0.5)
        _assert_odom_equals_gt(sim)
    x, y, yaw = sim.ground_truth()[:3]
    assert math.hypot(x - 0.5, y + 0.5) < 0.01
    assert abs(yaw - 0.7) < 0.005


def test_body_frame_command_moves_along_heading(robot):
    """vx in the body frame of a base rotated by 0.7 rad moves along (cos .7, sin .7) in the world."""
    sim = make_sim(robot, {**BIG, "start": [0.0, 0.0, 0.7]})
    drive(sim, 0.5, 0.0, 0.0, 2.0)
    x, y = sim.ground_truth()[:2]
    assert abs(math.atan2(y, x) - 0.7) < 1e-3


def test_limits_clamp_and_acceleration(robot):
    sim = make_sim(robot, BIG)
    st = sim.set_cmd_vel(5.0, -5.0, 10.0)
    assert st.clamped
    assert (st.vx, st.vy, st.wz) == (0.5, -0.5, 1.9)
    sim.step_for(0.1)  # yaw accel limit 3 rad/s^2
    assert 0.25 < sim.ground_truth()[5] <= 0.3 + 1e-6
    sim.reset()
    sim.set_cmd_vel(5.0, -5.0, 0.0)
    sim.step_for(0.1)  # linear accel limit 1.5 m/s^2 (without rotation, body and world frames agree)
    _, _, _, vx, vy, _ = sim.ground_truth()
    assert 0.13 < vx <= 0.15 + 1e-6
    assert -0.15 - 1e-6 <= vy < -0.13
    drive(sim, 5.0, -5.0, 10.0, 1.5)
    _, _, _, vx, vy, wz = sim.ground_truth()
    assert abs(vx - 0.5) < 0.01
    assert abs(vy + 0.5) < 0.01
    assert abs(wz - 1.9) < 0.01


def test_stale_command_stops_the_base(robot):
    sim = make_sim(robot, BIG)
    sim.set_cmd_vel(0.5, 0.0, 0.0)
    sim.step_for(2.0)
    gt = sim.ground_truth()
    assert abs(gt[3]) < 1e-3  # stopped after cmd_vel_timeout
    # moved ~ 0.5 s worth (accelerate, cruise until timeout, decelerate), far less than 2 s worth
    assert 0.15 < gt[0] < 0.3
    st = sim.set_cmd_vel(0.5, 0.0, 0.0, stamp=sim.time - 1.0)  # already older than the timeout
    assert st.rejected
    sim.step_for(0.5)
    assert abs(sim.ground_truth()[0] - gt[0]) < 1e-6


def test_nonplanar_components_ignored_with_one_warning(robot):
    sim = make_sim(robot, BIG)
    assert sim.set_cmd_vel(0.2, 0.0, 0.0, vz=1.0, wx=0.3).nonplanar_ignored
    sim.set_cmd_vel(0.2, 0.0, 0.0, wy=0.3)
    assert len([w for w in sim.warnings if "ignored" in w]) == 1
    assert sim.set_cmd_vel(float("nan"), 0.0, 0.0).rejected


def test_odometry_drift_is_seeded_and_bounded(robot):
    def run(seed: int):
        sim = make_sim(robot, BIG, seed=seed, odom_noise=OdomNoise.realistic())
        drive(sim, 0.4, 0.0, 0.3, 6.0)
        return np.array(sim.ground_truth()[:3]), np.array([sim.odometry().x, sim.odometry().y])

    gt_a, od_a = run(1)
    gt_b, od_b = run(1)
    _, od_c = run(2)
    assert np.array_equal(od_a, od_b)  # same seed, same drift
    assert not np.allclose(od_a, od_c)
    err = np.linalg.norm(od_a - gt_a[:2])
    assert 1e-4 < err < 0.2  # drifts, but a few percent of ~2.4 m travelled


def test_odometry_frame_at_start_option(robot):
    sim = make_sim(robot, {**BIG, "start": [1.0, 2.0, 0.5]}, odom_frame_at_start=True)
    drive(sim, 0.4, 0.0, 0.0, 1.0)
    od, gt = sim.odometry(), sim.ground_truth()
    assert abs(od.yaw) < 1e-6
    assert od.y == pytest.approx(0.0, abs=1e-6)
    assert od.x == pytest.approx(math.hypot(gt[0] - 1.0, gt[1] - 2.0), abs=1e-6)


def test_reset_replays_identically(robot):
    sim = make_sim(robot, BIG, odom_noise=OdomNoise.realistic())
    drive(sim, 0.3, 0.1, 0.2, 1.0)
    first = (sim.ground_truth(), sim.odometry())
    sim.reset()
    assert sim.time == 0.0
    assert sim.ground_truth()[:3] == (0.0, 0.0, 0.0)
    drive(sim, 0.3, 0.1, 0.2, 1.0)
    assert (sim.ground_truth(), sim.odometry()) == first
