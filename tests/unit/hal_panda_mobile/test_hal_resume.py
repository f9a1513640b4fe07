"""A crash-restarted simulator continues the run (issue 37 item 1): clock ahead of the last one published,
base where it was, odometry where it was; a first start never resumes an old run."""

from __future__ import annotations

import math

from hal_panda_mobile.persist import PERIOD_S, SimContinuity
from robonix_api.runstate import StateFile

from .conftest import drive, make_sim, room

SCENE = room(6.0, 6.0)
CONFIG = {"scene": "test_room", "seed": 3}


def _driven(robot, tmp_path):
    sim = make_sim(robot, SCENE)
    cont = SimContinuity(StateFile(tmp_path / "hal-sim.json"), "fp")
    for _ in range(30):  # 3 s of driving an arc, the state saved as the loop saves it
        drive(sim, 0.4, 0.0, 0.3, 0.1)
        doc = cont.maybe_save(sim, sim.time)
        if doc is not None:
            cont.write(doc)
    return sim, cont


def test_restart_resumes_clock_pose_and_odometry(robot, tmp_path):
    sim, cont = _driven(robot, tmp_path)
    t_crash, gt, od = sim.time, sim.ground_truth(), sim.odometry()
    fresh = make_sim(robot, SCENE)
    assert fresh.time == 0.0
    assert math.hypot(fresh.ground_truth()[0] - gt[0], fresh.ground_truth()[1] - gt[1]) > 0.5
    note = SimContinuity(StateFile(tmp_path / "hal-sim.json"), "fp").resume_into(fresh, allowed=True)
    assert note.startswith("resumed"), note
    # never behind the clock the dead process published; at most one save period + margin ahead
    assert t_crash < fresh.time <= t_crash + 2 * PERIOD_S + 0.1, (t_crash, fresh.time)
    g2, o2 = fresh.ground_truth(), fresh.odometry()
    assert math.hypot(g2[0] - gt[0], g2[1] - gt[1]) < 0.1  # where it was (minus < one save period of motion)
    assert max(abs(v) for v in g2[3:]) < 1e-9  # at rest
    # odom→base consistent with the truth: odometry moved exactly as the base did since the save
    assert math.hypot(o2.x - od.x, o2.y - od.y) < 0.1
    assert abs((o2.x - od.x) - (g2[0] - gt[0])) < 1e-6
    assert abs((o2.y - od.y) - (g2[1] - gt[1])) < 1e-6
    drive(fresh, 0.3, 0.0, 0.0, 1.0)  # and it drives on from there
    assert math.hypot(fresh.ground_truth()[0] - g2[0], fresh.ground_truth()[1] - g2[1]) > 0.1


def test_first_start_or_other_config_never_resumes(robot, tmp_path):
    _driven(robot, tmp_path)
    path = tmp_path / "hal-sim.json"
    other = make_sim(robot, SCENE)
    assert "another config" in SimContinuity(StateFile(path), "other-fp").resume_into(other, allowed=True)
    assert other.time == 0.0
    assert not path.exists()
    _driven(robot, tmp_path)
    first = make_sim(robot, SCENE)
    assert "not a restart" in SimContinuity(StateFile(path), "fp").resume_into(first, allowed=False)
    assert first.time == 0.0
    assert not path.exists()
