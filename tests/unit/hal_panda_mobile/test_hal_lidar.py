"""Ray-cast lidar: analytic ranges, heading from the body rotation, never seeing the robot, REP-117."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from hal_panda_mobile.files import load_scene, robot_from_dict
from hal_panda_mobile.sim import LidarNoise

from .conftest import make_sim, ray_distances, room

# inner faces of room(4, 3, t=0.2): x = +-3.9, y = +-2.9 (independent of the sim's wall code)
ROOM_RECTS = [(0.0, -3.0, 8.2, 0.2, 0.0), (0.0, 3.0, 8.2, 0.2, 0.0), (-4.0, 0.0, 0.2, 6.2, 0.0),
              (4.0, 0.0, 0.2, 6.2, 0.0)]
BOX = (2.2, 1.3, 1.0, 0.6, 0.4)
CYL = (-2.0, -1.5, 0.3)
SCENE = room(boxes=[{"center": BOX[:2], "size": BOX[2:4], "yaw": BOX[4], "height": 1.0}],
             cylinders=[{"center": CYL[:2], "radius": CYL[2], "height": 1.0}])


def _robot_with(robot, **lidar):
    data = dataclasses.asdict(robot)
    data["lidar"].update(lidar)
    return robot_from_dict(data)


@pytest.mark.parametrize("pose", [(0.0, 0.0, 0.0), (0.5, -0.3, 0.7), (-1.0, 1.2, -2.3)])
@pytest.mark.parametrize("mount", [(0.0, 0.0, 0.35, 0.0), (0.2, -0.1, 0.4, 0.5)])
def test_ranges_match_analytic_walls(robot, pose, mount):
    """<= 1 cm everywhere, with the base spawned rotated and the lidar mounted off-centre and yawed:
    a heading taken from anything but the body's world rotation shifts every beam and fails this."""
    r = _robot_with(robot, mount=mount)
    sim = make_sim(r, {**SCENE, "start": list(pose)})
    scan = sim.scan()
    x, y, yaw = pose
    mx, my, _, myaw = mount
    origin = (x + math.cos(yaw) * mx - math.sin(yaw) * my, y + math.sin(yaw) * mx + math.cos(yaw) * my)
    expected = ray_distances(origin, yaw + myaw + scan.angles(), ROOM_RECTS + [BOX], [CYL])
    assert np.all(np.isfinite(scan.ranges))
    assert np.max(np.abs(scan.ranges - expected)) < 0.01
    assert len(scan.ranges) == 360
    assert scan.ranges.dtype == np.float32
    assert scan.angle_min == pytest.approx(-math.pi)
    assert scan.angle_max < math.pi


def test_heading_follows_rotation_after_driving(robot):
    sim = make_sim(robot, SCENE)
    for _ in range(10):  # turn in place ~ 1 rad
        sim.set_cmd_vel(0.0, 0.0, 1.0)
        sim.step(50)
    sim.stop()
    sim.step_for(0.5)
    x, y, yaw = sim.ground_truth()[:3]
    scan = sim.scan()
    expected = ray_distances((x, y), yaw + scan.angles(), ROOM_RECTS + [BOX], [CYL])
    assert yaw > 0.5
    assert np.max(np.abs(scan.ranges - expected)) < 0.01


def test_robot_never_sees_itself(robot):
    """Lidar mounted *inside* the collision box (z 0.15 < height 0.30): without the exclusion every beam
    would return ~0.25-0.43 m; the nearest wall is >= 2.9 m away."""
    r = _robot_with(robot, mount=(0.0, 0.0, 0.15, 0.0))
    sim = make_sim(r, room())
    ranges = sim.scan().ranges
    assert ranges.min() > 2.8 > r.footprint_radius
    assert make_sim(robot, room()).scan().ranges.min() > robot.footprint_radius


def test_no_hit_is_plus_inf_and_too_close_is_minus_inf(robot):
    sim = make_sim(_robot_with(robot, range_max=2.0), room())
    assert np.all(np.isposinf(sim.scan().ranges))  # walls are >= 2.9 m away
    near = make_sim(_robot_with(robot, range_min=1.0), room(start=[3.3, 0.0, 0.0]))
    r = near.scan().ranges
    assert np.isneginf(r[180])  # beam 180 points along +x, the wall is 0.6 m ahead
    assert np.all(np.isfinite(r[:90]))


def test_noise_and_dropouts_seeded(robot):
    sim_clean = make_sim(robot, room())
    clean = sim_clean.scan().ranges

    def noisy(seed):
        sim = make_sim(robot, room(), seed=seed, lidar_noise=LidarNoise(noise_std=0.02, dropout_prob=0.25))
        return sim.scan().ranges

    a, b, c = noisy(3), noisy(3), noisy(4)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    drop = np.isposinf(a)
    assert 0.15 < drop.mean() < 0.35
    err = (a - clean)[~drop]
    assert 0.01 < err.std() < 0.03
    assert abs(err.mean()) < 0.005


def test_scan_stamp_is_sim_time(robot):
    sim = make_sim(robot, dataclasses.asdict(load_scene("apartment")))
    sim.step(123)
    assert sim.scan().stamp == pytest.approx(123 * 0.002)
