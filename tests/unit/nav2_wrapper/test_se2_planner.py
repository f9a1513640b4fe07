"""The footprint-aware (x, y, heading) fallback planner and its use after the 2D plan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nav2_wrapper.core.controller import ControllerConfig
from nav2_wrapper.core.costmap import Costmap, CostmapConfig
from nav2_wrapper.core.costs import LETHAL
from nav2_wrapper.core.footprint import Footprint
from nav2_wrapper.core.footprint_planning import FootprintAwarePlanner
from nav2_wrapper.core.headings import assign_headings
from nav2_wrapper.core.mppi import MppiController
from nav2_wrapper.core.navigator import RUNNING, NavConfig, Navigator
from nav2_wrapper.core.planner import GlobalPlanner, PlannerConfig
from nav2_wrapper.core.se2_planner import Se2Planner, Se2PlannerConfig, kernel_rows
from robonix_common.grid import GridMap

RES = 0.05
FOOTPRINT = Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))
FINE_OUTLINE = FOOTPRINT.outline_points(0.02)
START, GOAL = (4.0, 1.5, math.pi / 2), (4.0, 6.5)


def _cells(v: float) -> int:
    return int(round(v / RES))


def _world(slot: bool) -> Costmap:
    """8 × 8 m; a 1.5 m thick wall across it (y 3.25-4.75) pierced by a dogleg channel 0.55 m wide near x = 4
    (the inscribed disc fits along it, but the 0.70 × 0.50 m body cannot turn its right-angle corners) and,
    optionally, a straight slot 0.70 m wide at x 1.0-1.7: narrower than the circumscribed circle (0.86 m),
    so the body fits only held lengthwise."""
    g = np.zeros((160, 160), np.int8)
    g[_cells(3.25):_cells(4.75), :] = 100

    def free(x0: float, x1: float, y0: float, y1: float) -> None:
        g[_cells(y0):_cells(y1), _cells(x0):_cells(x1)] = 0

    free(3.75, 4.30, 3.25, 4.30)
    free(3.75, 5.10, 3.75, 4.30)
    free(4.55, 5.10, 3.75, 4.75)
    if slot:
        free(1.0, 1.7, 3.25, 4.75)
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    cm.set_static_map(GridMap(g, RES))
    return cm


def _plan_2d(cm: Costmap) -> np.ndarray:
    res = GlobalPlanner().plan(cm, START[:2], GOAL)
    assert res.ok
    return res.path


def _se2(cm: Costmap, guide: np.ndarray | None, **kw: object) -> object:
    planner = Se2Planner(Se2PlannerConfig(**kw), FOOTPRINT)   # type: ignore[arg-type]
    return planner.plan(cm, START, GOAL, GlobalPlanner().traversal_table(), guide=guide)


def _lethal_contacts(cm: Costmap, path: np.ndarray, headings: np.ndarray) -> int:
    poses = np.column_stack([path, headings])
    return int((cm.footprint_costs(poses, FINE_OUTLINE, outside=0) == LETHAL).any(axis=1).sum())


def test_the_2d_route_through_the_dogleg_has_no_fitting_heading_and_se2_takes_the_slot_lengthwise() -> None:
    cm = _world(slot=True)
    path2d = _plan_2d(cm)
    assert np.all(path2d[:, 0] > 3.5)                                   # the 2D plan takes the short dogleg
    assert not assign_headings(path2d, cm, FOOTPRINT.outline_points(0.05)).feasible
    plan = _se2(cm, path2d)
    assert plan.ok, plan.reason
    assert np.allclose(plan.path[0], START[:2])
    assert np.allclose(plan.path[-1], GOAL)
    in_wall = (plan.path[:, 1] > 3.3) & (plan.path[:, 1] < 4.7)
    assert in_wall.any()
    assert np.all(np.abs(plan.path[in_wall, 0] - 1.35) < 0.1)
    yaw = np.mod(plan.headings[in_wall], math.pi)
    assert np.all(np.abs(yaw - math.pi / 2) < math.radians(10))         # held lengthwise through it
    assert _lethal_contacts(cm, plan.path, plan.headings) == 0
    steps = np.hypot(*np.diff(plan.path, axis=0).T)
    assert steps.max() <= RES + 1e-9                                     # dense, as the controllers expect


def test_no_heading_fits_anywhere_then_se2_reports_no_path() -> None:
    cm = _world(slot=False)
    plan = _se2(cm, _plan_2d(cm))
    assert not plan.ok
    assert "cut off" in plan.reason


def test_every_pose_of_a_cluttered_se2_path_is_clear_of_lethal_cells() -> None:
    """Soundness on random posts: the motion the path describes is collision-free with the true footprint —
    translating from each point to the next at the first one's heading, then turning in place (the short way,
    as the controllers turn) to the next point's heading."""
    rng = np.random.default_rng(2)
    g = np.zeros((140, 120), np.int8)
    for _ in range(45):
        r, c = rng.integers(30, 110), rng.integers(0, 117)
        g[r:r + 3, c:c + 3] = 100
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    cm.set_static_map(GridMap(g, RES))
    plan = Se2Planner(Se2PlannerConfig(), FOOTPRINT).plan(cm, (3.0, 0.6, 0.0), (3.0, 6.4),
                                                          GlobalPlanner().traversal_table())
    assert plan.ok, plan.reason
    assert _lethal_contacts(cm, plan.path, plan.headings) == 0
    assert _lethal_contacts(cm, plan.path[1:], plan.headings[:-1]) == 0          # arriving before a turn
    turn = (np.mod(np.diff(plan.headings) + math.pi / 2, math.pi) - math.pi / 2)  # short way, modulo a half turn
    turning = np.flatnonzero(np.abs(turn) > 1e-9)
    assert len(turning) >= 3                                                      # the field makes it turn
    frac = np.linspace(0.0, 1.0, 11)
    for i in turning:
        yaws = plan.headings[i] + frac * turn[i]
        pts = np.repeat(plan.path[i + 1][None], len(frac), axis=0)
        assert _lethal_contacts(cm, pts, yaws) == 0


def test_the_search_stops_at_max_expansions() -> None:
    cm = _world(slot=True)
    plan = _se2(cm, _plan_2d(cm), max_expansions=1000)
    assert not plan.ok
    assert plan.expansions == 1000
    assert "max_expansions" in plan.reason


@pytest.mark.parametrize("yaw", [0.0, 0.3, math.pi / 4, 1.2, math.pi / 2])
def test_kernel_rows_cover_exactly_the_cells_the_rectangle_overlaps(yaw: float) -> None:
    """Against a dense point sampling of the turned rectangle: every cell holding a sample is in the kernel,
    and every kernel cell lies within half a cell's diagonal of the rectangle."""
    hl, hw = 0.36, 0.26
    pad, lo, hi = kernel_rows(hl, hw, yaw, RES)
    inside = {(di, dj) for k, di in enumerate(range(-pad, pad + 1)) for dj in range(lo[k], hi[k] + 1)}
    u, v = np.meshgrid(np.linspace(-hl, hl, 200), np.linspace(-hw, hw, 150))
    x, y = u * math.cos(yaw) - v * math.sin(yaw), u * math.sin(yaw) + v * math.cos(yaw)
    covered = set(zip(np.round(y / RES).astype(int).ravel(), np.round(x / RES).astype(int).ravel(), strict=True))
    assert covered <= inside
    for di, dj in inside:
        cx, cy = dj * RES, di * RES
        bu, bv = cx * math.cos(yaw) + cy * math.sin(yaw), -cx * math.sin(yaw) + cy * math.cos(yaw)
        gap = math.hypot(max(abs(bu) - hl, 0.0), max(abs(bv) - hw, 0.0))
        assert gap <= RES / math.sqrt(2) + 1e-9


def test_the_navigator_side_keeps_a_fitting_2d_plan_and_replaces_one_that_does_not_fit() -> None:
    open_map = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    open_map.set_static_map(GridMap(np.zeros((160, 160), np.int8), RES))
    gp = GlobalPlanner(PlannerConfig())
    fap = FootprintAwarePlanner(gp, FOOTPRINT)
    res = gp.plan(open_map, START[:2], GOAL)
    assert fap.refine(open_map, START, GOAL, res) is res
    assert fap.stats.runs == 0
    cm = _world(slot=True)
    res = gp.plan(cm, START[:2], GOAL)
    out = fap.refine(cm, START, GOAL, res)
    assert out.headings is not None
    assert len(out.headings) == len(out.path)
    assert out.path[:, 0].min() < 2.0
    assert fap.stats.found == 1
    off = FootprintAwarePlanner(GlobalPlanner(PlannerConfig(se2=Se2PlannerConfig(enabled=False))), FOOTPRINT)
    assert off.refine(cm, START, GOAL, res) is res


def test_the_controllers_hold_the_planned_heading_and_keep_it_across_a_restart() -> None:
    cm = _world(slot=True)
    plan = _se2(cm, _plan_2d(cm))
    ctl = MppiController(ControllerConfig(footprint=FOOTPRINT))
    ctl.set_path(plan.path, plan.headings)
    in_wall = int(np.flatnonzero(plan.path[:, 1] > 3.5)[0])
    x, y = plan.path[in_wall]
    ctl.progress_index = -1
    i = ctl._closest(x, y)
    target = ctl._heading_target(i, (x, y, 0.2), (*GOAL, 0.0), cm)
    assert abs(math.sin(target)) > math.cos(math.radians(10))      # along the slot, whatever the yaw now
    ctl.set_path(ctl.path)                                           # what the navigator does after a recovery
    assert ctl.path_headings is not None
    ctl.set_path(plan.path[:10])                                     # a new plain path drops them
    assert ctl.path_headings is None
    with pytest.raises(ValueError, match="headings for"):
        ctl.set_path(plan.path, plan.headings[:-1])


def test_the_navigator_plans_the_slot_route_and_hands_its_headings_to_the_controller() -> None:
    cm = _world(slot=True)
    grid = GridMap(np.where(cm.static == LETHAL, 100, 0).astype(np.int8), RES)
    cfg = NavConfig.defaults(FOOTPRINT)
    cfg.mppi = None
    nav = Navigator(cfg)
    nav.tick(0.0, START, grid=grid)
    rec = nav.navigate(GOAL[0], GOAL[1], math.pi / 2, now=0.0)
    nav.tick(0.05, START)
    assert rec.state == RUNNING
    assert nav.controller.path_headings is not None
    assert nav.path[:, 0].min() < 2.0                                 # the slot, not the dogleg
    assert nav.footprint_planner.stats.found == 1


@pytest.mark.parametrize("posts", [0, 45])
def test_the_distance_shortcut_leaves_the_collision_grids_unchanged(posts: int,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """Cells decided from the distance transform (free or blocked at every heading) match the per-heading test."""
    rng = np.random.default_rng(2)
    g = np.zeros((100, 90), np.int8)
    for _ in range(posts):
        r, c = rng.integers(0, 97), rng.integers(0, 87)
        g[r:r + 3, c:c + 3] = 100
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    cm.set_static_map(GridMap(g, RES))
    planner = Se2Planner(Se2PlannerConfig(), FOOTPRINT)
    win = planner._window(cm, np.array([[1.0, 1.0], [3.5, 4.0]]), 1.0)
    fast = planner.blocked_grids(cm, win)
    monkeypatch.setattr(planner, "_decided", lambda lethal, pad, res: np.full(
        (lethal.shape[0] - 2 * pad, lethal.shape[1] - 2 * pad), 2, np.uint8))
    assert np.array_equal(fast, planner.blocked_grids(cm, win))
    assert fast.any() == (posts > 0)


def test_a_still_fitting_se2_path_is_reused_at_the_next_replan_and_searched_again_once_blocked() -> None:
    cm = _world(slot=True)
    gp = GlobalPlanner(PlannerConfig())
    fap = FootprintAwarePlanner(gp, FOOTPRINT)
    first = fap.refine(cm, START, GOAL, gp.plan(cm, START[:2], GOAL))
    assert fap.stats.runs == 1
    assert first.headings is not None
    k = 6                                  # near the start: the 2D plan from here still takes the dogleg
    pose = (float(first.path[k, 0]), float(first.path[k, 1]), float(first.headings[k]))
    again = fap.refine(cm, pose, GOAL, gp.plan(cm, pose[:2], GOAL))
    assert (fap.stats.runs, fap.stats.reuses) == (1, 1)
    assert np.allclose(again.path, first.path[k:])
    assert np.allclose(again.headings, first.headings[k:])
    assert again.length < first.length
    # the slot closes: the kept path no longer fits, so the search runs again (and finds no route)
    g = np.where(cm.static == LETHAL, 100, 0).astype(np.int8)
    g[_cells(3.25):_cells(4.75), _cells(1.2):_cells(1.5)] = 100
    cm.set_static_map(GridMap(g, RES))
    res = gp.plan(cm, pose[:2], GOAL)
    assert fap.refine(cm, pose, GOAL, res) is res
    assert (fap.stats.runs, fap.stats.reuses) == (2, 1)
    # another goal is never served from the kept path
    fap.refine(_world(slot=True), START, GOAL, gp.plan(_world(slot=True), START[:2], GOAL))
    assert fap.stats.runs == 3
    fap.refine(cm, START, (4.2, 6.5), gp.plan(cm, START[:2], (4.2, 6.5)))
    assert (fap.stats.runs, fap.stats.reuses) == (4, 1)


def test_a_search_run_in_slices_finds_the_same_path_as_in_one_go() -> None:
    cm = _world(slot=True)
    guide = _plan_2d(cm)
    whole = _se2(cm, guide)
    planner = Se2Planner(Se2PlannerConfig(), FOOTPRINT)
    search = planner.begin(cm, START, GOAL, GlobalPlanner().traversal_table(), guide=guide)
    assert not isinstance(search, type(whole))
    search.hk, search.hv = search.hk[:16], search.hv[:16]     # the heap must grow on the way, too
    slices, out = 0, None
    while out is None:
        out = search.advance(1000)
        slices += 1
    assert out.ok
    assert slices > 2
    assert out.expansions == whole.expansions
    assert np.array_equal(out.path, whole.path)
    assert np.array_equal(out.headings, whole.headings)


def test_the_navigator_follows_its_path_while_a_search_runs_in_slices_then_takes_the_se2_path() -> None:
    cm = _world(slot=True)
    grid = GridMap(np.where(cm.static == LETHAL, 100, 0).astype(np.int8), RES)
    cfg = NavConfig.defaults(FOOTPRINT)
    cfg.mppi = None
    cfg.planner.se2.tick_expansions = 1000
    nav = Navigator(cfg)
    nav.tick(0.0, START, grid=grid)
    nav.navigate(GOAL[0], GOAL[1], math.pi / 2, now=0.0)
    nav.tick(0.05, START)                       # the first plan: no path to follow yet, so searched to the end
    first = nav.path
    assert nav.footprint_planner.stats.found == 1
    assert not nav.footprint_planner.pending
    nav.footprint_planner.forget()               # as if the kept path no longer fitted: the next replan searches
    t, ticks = 1.1, 0
    nav.tick(t, START)
    while nav.footprint_planner.pending:
        assert nav.path is first                  # followed unchanged meanwhile
        t, ticks = t + 0.05, ticks + 1
        nav.tick(t, START)
    assert ticks >= 2
    assert nav.footprint_planner.stats.runs == 2
    assert nav.path is not first
    assert nav.path[:, 0].min() < 2.0            # the slot route again
    assert nav.controller.path_headings is not None


def test_a_kept_route_that_no_longer_fits_at_its_own_headings_is_kept_with_new_ones_that_fit() -> None:
    cm = _world(slot=True)
    gp = GlobalPlanner(PlannerConfig())
    fap = FootprintAwarePlanner(gp, FOOTPRINT)
    first = fap.refine(cm, START, GOAL, gp.plan(cm, START[:2], GOAL))
    assert fap._kept is not None
    in_wall = (fap._kept.path[:, 1] > 3.3) & (fap._kept.path[:, 1] < 4.7)
    fap._kept.headings = fap._kept.headings.copy()
    fap._kept.headings[in_wall] = 0.0              # crosswise: the 0.70 m slot does not take the body so
    pose = (float(first.path[6, 0]), float(first.path[6, 1]), float(first.headings[6]))
    again = fap.refine(cm, pose, GOAL, gp.plan(cm, pose[:2], GOAL))
    assert (fap.stats.runs, fap.stats.reuses, fap.stats.reheaded) == (1, 1, 1)
    assert np.allclose(again.path, first.path[6:])
    wall = (again.path[:, 1] > 3.3) & (again.path[:, 1] < 4.7)
    assert np.all(np.abs(np.mod(again.headings[wall], math.pi) - math.pi / 2) < math.radians(15))
    assert _lethal_contacts(cm, again.path, again.headings) == 0


def _straight_channel(cm: Costmap) -> Costmap:
    """The same world seen from afar through a noisy map: the dogleg looks like a straight 0.85 m channel
    (wide enough for the body held lengthwise)."""
    g = np.where(cm.static == LETHAL, 100, 0).astype(np.int8)
    g[_cells(3.25):_cells(4.75), _cells(3.75):_cells(4.60)] = 0
    out = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT))
    out.set_static_map(GridMap(g, RES))
    return out


def test_a_gap_found_too_narrow_stays_avoided_until_the_robot_is_back_near_it() -> None:
    close = _world(slot=True)            # first-hand view: the dogleg is too narrow for the body
    near = (4.0, 2.2, math.pi / 2)
    gp = GlobalPlanner(PlannerConfig())
    fap = FootprintAwarePlanner(gp, FOOTPRINT)
    first = fap.refine(close, near, GOAL, gp.plan(close, near[:2], GOAL))
    assert first.path[:, 0].min() < 2.0  # the slot route
    (sx, sy, seen_from), = fap.tight_spots
    assert abs(sx - 4.0) < 0.2, fap.tight_spots   # where the body meets the wall below the dogleg
    assert 2.7 < sy < 3.3, fap.tight_spots
    far = _straight_channel(close)
    # from the start, farther from the spot than it was judged from, the channel looks open ...
    assert math.hypot(START[0] - sx, START[1] - sy) > seen_from + 0.5
    straight = gp.plan(far, START[:2], GOAL)
    fresh = FootprintAwarePlanner(gp, FOOTPRINT)
    assert fresh.refine(far, START, GOAL, straight) is straight    # without the memory: into the channel
    # ... but the remembered spot keeps the robot on the slot route
    kept = fap.refine(far, START, GOAL, straight)
    assert kept is not straight
    assert kept.path[:, 0].min() < 2.0
    assert fap.stats.tight_spots == 1
    # back near the spot the map is first-hand again and decides (here: the channel is open)
    assert fap.refine(far, near, GOAL, gp.plan(far, near[:2], GOAL)).path[:, 0].min() > 3.0
    assert fap.tight_spots == ()
