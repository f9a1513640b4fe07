"""Contact with the world: walls stop the base, collisions are reported once per episode."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal_panda_mobile.sim import SimConfigError

from .conftest import drive, make_sim, room

WALL_SCENE = room(
    6.0, 4.0, boxes=[{"center": [2.1, 0.0], "size": [0.2, 4.0], "height": 1.0, "name": "barrier"}])
# barrier's near face at x = 2.0; the base's front is 0.35 m ahead of its centre


@pytest.mark.parametrize("yaw", [0.0, 0.4])
def test_driving_into_a_wall_stops_and_reports_once(robot, yaw):
    sim = make_sim(robot, {**WALL_SCENE, "start": [0.0, 0.0, yaw]})
    max_x = -math.inf
    vx, vy = math.cos(yaw) * 0.5, -math.sin(yaw) * 0.5  # world +x expressed in the body frame
    for _ in range(80):  # 8 s at full speed: would be 4 m without the barrier
        sim.set_cmd_vel(vx, vy, 0.0)
        sim.step(50)
        max_x = max(max_x, sim.ground_truth()[0])
    reach = 0.35 * math.cos(yaw) + 0.25 * math.sin(yaw)  # half-extent of the rotated footprint along x
    assert max_x < 2.0 - reach + 0.01  # never through; at most 1 cm of soft-contact penetration
    assert max_x > 2.0 - reach - 0.05  # and it did reach the barrier
    events = sim.collisions()
    assert len(events) == 1  # pushing for seconds is one episode
    ev = events[0]
    assert ev.other_geom == "barrier"
    assert ev.robot_geom == "robot/base"
    assert 2.0 - 0.02 < ev.x < 2.0 + 0.02
    assert 1.0 < ev.time < 5.0
    assert sim.collisions(since=ev.time) == []


def test_separate_contacts_are_separate_events(robot):
    sim = make_sim(robot, WALL_SCENE)
    drive(sim, 0.5, 0.0, 0.0, 5.0)
    drive(sim, -0.5, 0.0, 0.0, 1.0)  # back off for longer than the debounce
    drive(sim, 0.5, 0.0, 0.0, 2.0)
    events = sim.collisions()
    assert len(events) == 2
    assert events[1].time > events[0].time + 1.0


def test_teleport_rejects_collision_and_names_obstacle(robot):
    sim = make_sim(robot, WALL_SCENE)
    with pytest.raises(SimConfigError, match="barrier"):
        sim.teleport(2.0, 0.0, 0.0)
    sim.teleport(-1.0, 1.0, 1.0)
    assert np.allclose(sim.ground_truth()[:3], (-1.0, 1.0, 1.0))
    od = sim.odometry()
    assert (od.x, od.y) == pytest.approx((-1.0, 1.0))


def test_teleport_without_odom_reset_does_not_integrate_the_jump(robot):
    sim = make_sim(robot, WALL_SCENE)
    sim.teleport(-2.0, 1.0, 0.0, reset_odom=False)
    drive(sim, 0.4, 0.0, 0.0, 1.0)
    od, gt = sim.odometry(), sim.ground_truth()
    assert (od.x - 0.0, od.y) == pytest.approx((gt[0] + 2.0, 0.0), abs=1e-6)


def test_spawn_box_is_seen_and_collides_then_reset_removes_it(robot):
    sim = make_sim(robot, room(6.0, 4.0))
    drive(sim, 0.3, 0.0, 0.0, 1.0)
    before = sim.ground_truth()
    sim.spawn_box("crate", -2.0, 0.0, 0.5, 0.5)
    assert sim.ground_truth() == before  # state carried over the recompile
    assert sim.scan().ranges[0] == pytest.approx(abs(-2.0 + 0.25 - before[0]), abs=0.01)  # beam 0 looks at -x
    with pytest.raises(SimConfigError, match="overlap the robot"):
        sim.spawn_box("on_me", before[0], 0.0, 0.3, 0.3)
    with pytest.raises(SimConfigError, match="already used"):
        sim.spawn_box("crate", 3.0, 3.0, 0.3, 0.3)
    assert any(o["name"] == "crate" for o in sim.scene_info()["obstacles"])
    drive(sim, -0.5, 0.0, 0.0, 6.0)
    assert sim.collisions()[-1].other_geom == "crate"
    assert sim.ground_truth()[0] > -2.0 + 0.25 + 0.35 - 0.01
    sim.reset()
    assert all(o["name"] != "crate" for o in sim.scene_info()["obstacles"])
    assert sim.scan().ranges[0] > 5.0


def test_thin_wall_and_spawn_during_contact_keep_one_episode(robot):
    """A 2 cm wall still stops the base; recompiling the model (spawn_box) mid-contact does not start
    a second collision episode."""
    thin = room(6.0, 4.0, boxes=[{"center": [2.01, 0.0], "size": [0.02, 4.0], "height": 1.0, "name": "foil"}])
    sim = make_sim(robot, thin)
    drive(sim, 0.5, 0.0, 0.0, 6.0)
    assert sim.ground_truth()[0] < 2.0 - 0.35 + 0.01
    sim.spawn_box("crate", -3.0, 2.0, 0.4, 0.4)
    drive(sim, 0.5, 0.0, 0.0, 1.0)
    assert [e.other_geom for e in sim.collisions()] == ["foil"]
