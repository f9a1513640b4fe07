"""Navigation events in the MuJoCo loop: a box dropped into the path, and a goal inside a closed room."""

from __future__ import annotations

import math

import numpy as np

from robonix_eval.pipeline import Pipeline, PipelineOptions

BOX = (8.0, 5.75, 0.6, 0.7)  # x, y, sx, sy: across the planned path (y 6.0-6.11), passable on the north side


def _box_across(path: np.ndarray) -> tuple[float, float, float, float]:
    """BOX, its top edge raised to 5 cm past the planned path where that path runs at x = BOX x: where the
    path lies in the corridor's cost-free band depends on where the robot was when it planned."""
    x, y, sx, sy = BOX
    order = np.argsort(path[:, 0])
    y_path = float(np.interp(x, path[order, 0], path[order, 1]))
    bottom, top = y - sy / 2, max(y + sy / 2, y_path + 0.05)
    return x, (bottom + top) / 2, sx, top - bottom


def test_box_in_path_triggers_replan_and_goal_succeeds() -> None:
    pipe = Pipeline(PipelineOptions(scene="office", seed=0))
    spawned: dict[str, object] = {}

    def drop_box(p: Pipeline) -> None:
        x, y, _ = p.ground_truth_pose()
        if not spawned and x > BOX[0] - 3.0:
            path = p.nav.path.copy()
            box = _box_across(path)
            p.sim.spawn_box("dropped", *box)
            spawned.update(t=p.time, plans=len(p.plan_times), path=path, box=box)

    pipe.hooks.append(drop_box)
    r = pipe.run_goals([(14.5, 6.0, 0.0)])[0]
    assert spawned, "the robot never came near the drop point"
    old, (bx, by, bsx, bsy) = spawned["path"], spawned["box"]
    inside = (np.abs(old[:, 0] - bx) < bsx / 2) & (np.abs(old[:, 1] - by) < bsy / 2)
    assert inside.any(), "the box was not dropped onto the planned path"
    assert len(pipe.plan_times) > spawned["plans"]
    new = pipe.nav.path
    clear = np.maximum(np.abs(new[:, 0] - bx) - bsx / 2, np.abs(new[:, 1] - by) - bsy / 2)
    assert clear.min() > 0.25  # the final plan passes the box by more than the inscribed radius
    assert r.state == "SUCCEEDED", r.detail
    assert r.collisions == 0
    assert r.within_tolerance


def test_goal_in_closed_room_fails_with_reason_and_robot_stops() -> None:
    pipe = Pipeline(PipelineOptions(scene="warehouse", seed=0))
    cx, cy, half, t = 3.0, 7.0, 0.8, 0.1  # a closed 1.6 m room in the west loading zone
    for name, x, y, sx, sy in (("room_s", cx, cy - half, 2 * half + t, t), ("room_n", cx, cy + half, 2 * half + t, t),
                               ("room_w", cx - half, cy, t, 2 * half + t), ("room_e", cx + half, cy, t, 2 * half + t)):
        pipe.sim.spawn_box(name, x, y, sx, sy, height=1.0)
    r = pipe.run_goals([(cx, cy, 0.0)])[0]
    assert r.state == "FAILED", r.detail
    assert "no path" in r.detail or "not reachable" in r.detail or "gave up" in r.detail, r.detail
    assert r.time < 120.0
    assert r.collisions == 0
    assert r.final_speed < 0.02
    assert math.isfinite(r.final_error_xy)
