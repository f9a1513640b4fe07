"""`rbnx demo`'s goal choice and nav-detail parsing behave as the live view and summary rely on (its usage
errors, which run the CLI, are in tests/integration/rbnx/test_demo_usage_errors.py)."""

from __future__ import annotations

import io
import math

import pytest

from rbnx.demo.goals import Goal, choose_goals, parse_detail, path_length
from rbnx.demo.report import GoalResult, goals_exit_code, print_table

KITCHEN = {"island_east": [5.8, 3.0], "pantry": [8.3, 6.8], "dining": [2.5, 6.2], "fridge": [8.5, 2.0]}


def test_goals_follow_file_order_skip_near_ones_and_cycle() -> None:
    goals = choose_goals(KITCHEN, (5.5, 3.0), 6)
    assert [g.name for g in goals] == ["pantry", "dining", "fridge", "island_east", "pantry", "dining"]


def test_goals_seed_is_deterministic_and_never_repeats_in_place() -> None:
    a = choose_goals(KITCHEN, (3.5, 1.6), 5, seed=3)
    assert a == choose_goals(KITCHEN, (3.5, 1.6), 5, seed=3)
    assert all(x != y for x, y in zip(a, a[1:], strict=False))


def test_goals_none_when_every_waypoint_is_too_close() -> None:
    assert choose_goals({"here": [0.0, 0.2]}, (0.0, 0.0), 3) == []
    assert choose_goals({}, (0.0, 0.0), 3) == []


def test_parse_detail_reads_the_nav_status_line() -> None:
    p = parse_detail("2.88 m remaining, ETA 6 s, 1 recoveries, blocked")
    assert (p.remaining_m, p.eta_s, p.recoveries) == (2.88, 6.0, 1)
    assert parse_detail("reached goal (0.21 m from it, 0 recoveries)").remaining_m is None


def test_path_length() -> None:
    assert path_length([(0, 0), (3, 4), (3, 5)]) == pytest.approx(6.0)
    assert path_length([(1, 1)]) == 0.0


def _contact() -> dict:
    return {"sim_time": 12.5, "robot_geom": "base", "other_geom": "wall_5", "x": 1.0, "y": 2.0}


def test_a_goal_reached_with_a_contact_is_a_failure_in_summary_table_and_exit_code() -> None:
    clean = GoalResult(1, Goal("a", 1.0, 1.0), state="SUCCEEDED")
    hit = GoalResult(2, Goal("b", 3.0, 1.0), state="SUCCEEDED", collisions=[_contact()])
    assert clean.succeeded
    assert hit.reached
    assert not hit.succeeded
    assert hit.outcome == "CONTACT"
    d = hit.as_dict()
    assert (d["reached"], d["succeeded"], d["collision_count"]) == (True, False, 1)
    assert d["failure"] == "contact with wall_5"
    assert "failure" not in clean.as_dict()
    assert goals_exit_code([clean], 1) == 0
    assert goals_exit_code([clean, hit], 2) == 1
    assert goals_exit_code([clean], 2) == 1               # a goal that never ran is not a success either
    out = io.StringIO()
    print_table([clean, hit], 2, out)
    text = out.getvalue()
    assert "CONTACT" in text
    assert "1/2 goals succeeded (1 reached with a contact: failed)" in text


def test_contacts_carry_the_robot_pose_and_the_nav_status_in_force() -> None:
    """A contact record says where the robot was just before it and what navigation was doing then."""
    import threading

    from rbnx.demo.goalrun import GoalRunner
    from rbnx.demo.record import Recorder
    from rbnx.demo.rpc import GroundTruth

    rec = Recorder(rpc=None, domain_id=0)  # type: ignore[arg-type]  # only its logs are used here
    rec.gt_odom += [(12.0, 1.0, 2.0, 0.5), (12.4, 1.1, 2.0, 0.6), (12.8, 1.2, 2.0, 0.7)]
    runner = GoalRunner(None, rec, None, threading.Event(), 10.0, None)  # type: ignore[arg-type]
    res = GoalResult(1, Goal("b", 3.0, 1.0), collisions=[_contact()])
    for t, detail in [(10.0, "2.90 m remaining, ETA 6 s, 0 recoveries"), (11.0, "2.10 m remaining, ETA 4 s, 0 "
                      "recoveries"), (12.0, "recovering: escape after: blocked (1 recoveries)"),
                      (13.0, "1.00 m remaining, ETA 2 s, 1 recoveries")]:
        rec.gt.append(GroundTruth(0.0, 0.0, 0.0, t))
        runner._note_status(res, "RUNNING", detail)
    assert [e["sim_time"] for e in res.nav_events] == [10.0, 12.0, 13.0]   # the countdown is one entry
    runner._contact_context(res)
    c = res.collisions[0]
    assert c["robot_pose"] == {"sim_time": 12.4, "x": 1.1, "y": 2.0, "theta": 0.6}
    assert c["nav_detail"].startswith("recovering: escape")
    assert "kind" not in res.as_dict()["nav_events"][0]


def test_clearance_is_the_footprint_outline_distance_to_the_nearest_obstacle() -> None:
    """A 0.7 x 0.5 m body beside a wall: the clearance is the gap between its side and the wall (within a
    cell), 0 once it overlaps, and the closest pose of a stretch is the one reported."""
    import numpy as np

    from robonix_eval.clearance import ClearanceField

    res = 0.02
    occ = np.zeros((200, 200), dtype=bool)          # 4 x 4 m from (0, 0); a wall filling x >= 3 m
    occ[:, 150:] = True
    fp = [(0.35, 0.25), (-0.35, 0.25), (-0.35, -0.25), (0.35, -0.25)]
    field = ClearanceField(occ, (0.0, 0.0), res, fp)
    # facing the wall, the front edge at x = 2.35 + 0.35: 0.30 m from it; turned 90° at x 2.2, the side at 2.45
    assert field.closest([(2.35, 2.0, 0.0)]).clearance_m == pytest.approx(0.30, abs=res)
    assert field.closest([(2.2, 2.0, math.pi / 2)]).clearance_m == pytest.approx(0.55, abs=res)
    near = field.closest([(1.0, 2.0, 0.0), (2.5, 2.0, 0.0), (2.0, 2.0, 0.0)])
    assert near.clearance_m == pytest.approx(0.15, abs=res)
    assert near.pose == (2.5, 2.0, 0.0)
    assert field.closest([(2.8, 2.0, 0.0)]).clearance_m == 0.0
    assert field.closest([]) is None
