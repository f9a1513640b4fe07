"""Heading assignment along a planned path, checked with the true rectangular footprint."""

from __future__ import annotations

import math

import numpy as np

from nav2_wrapper.core.costmap import Costmap, CostmapConfig
from nav2_wrapper.core.costs import LETHAL
from nav2_wrapper.core.footprint import Footprint
from nav2_wrapper.core.headings import HeadingConfig, assign_headings
from robonix_common.grid import GridMap

RES = 0.05
FOOTPRINT = Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))
OUTLINE = FOOTPRINT.outline_points(0.05)


def _costmap(barrier_gap: float | None) -> Costmap:
    """6 × 6 m; optionally an east-west wall at y = 3 with a centred gap (x = 3 ± gap/2)."""
    grid = np.zeros((120, 120), np.int8)
    if barrier_gap is not None:
        row = int(3.0 / RES)
        lo, hi = int(round((3.0 - barrier_gap / 2) / RES)), int(round((3.0 + barrier_gap / 2) / RES))
        grid[row - 1:row + 2, :lo] = 100
        grid[row - 1:row + 2, hi:] = 100
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT, inflation_layer=False))
    cm.set_static_map(GridMap(grid, RES))
    return cm


def _north_path() -> np.ndarray:
    return np.column_stack([np.full(61, 3.0), np.linspace(1.5, 4.5, 61)])


def test_open_space_headings_follow_the_path_direction() -> None:
    path = np.column_stack([np.linspace(1.0, 5.0, 81), np.linspace(1.0, 5.0, 81)])   # diagonal
    plan = assign_headings(path, _costmap(None), OUTLINE)
    assert plan.feasible
    assert np.allclose(np.mod(plan.headings, math.pi), math.pi / 4, atol=math.radians(5.1))


def test_a_gap_narrower_than_the_length_is_crossed_lengthwise() -> None:
    # 0.62 m gap: the 0.50 m width fits, the 0.70 m length does not; a start turned sideways must turn first
    cm = _costmap(0.62)
    plan = assign_headings(_north_path(), cm, OUTLINE, start_yaw=0.0)
    assert plan.feasible
    at_gap = np.argmin(np.abs(plan.points[:, 1] - 3.0))
    assert abs(math.sin(plan.headings[at_gap])) > math.cos(math.radians(12))   # within ~12° of north/south
    assert plan.headings[0] == 0.0
    d = np.mod(np.diff(plan.headings), math.pi)
    turn = np.minimum(d, math.pi - d)          # headings are modulo a half turn (either end may lead)
    cfg = HeadingConfig()
    assert turn.max() <= cfg.max_turn_per_m * cfg.spacing + math.pi / cfg.bins + 1e-9
    poses = np.column_stack([plan.points, plan.headings])
    assert not (cm.footprint_costs(poses, FOOTPRINT.outline_points(0.025), outside=0) == LETHAL).any()


def test_a_gap_narrower_than_the_body_blocks_at_the_gap() -> None:
    plan = assign_headings(_north_path(), _costmap(0.40), OUTLINE)
    assert not plan.feasible
    assert plan.blocked is not None
    assert 2.4 < plan.points[plan.blocked, 1] < 3.0     # the first point whose footprint reaches the wall
