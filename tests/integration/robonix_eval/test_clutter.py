"""Clutter worlds: the passability proof is sound at a known threshold, and worlds load into the simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_eval.clutter import ClutterSpec, FootprintBox, generate, post_field, prove_passable, world_rects

SPEC = ClutterSpec()
BOX = FootprintBox()


def _barrier(gap: float) -> list[tuple[float, float, float, float]]:
    """The three walls plus a 0.15 m thick barrier across the world at y = 6 with one centred gap."""
    _, walls = world_rects(np.zeros((1, 1), dtype=bool), SPEC)
    mid = SPEC.width / 2
    return walls + [(0.0, 5.925, mid - gap / 2, 6.075), (mid + gap / 2, 5.925, SPEC.width, 6.075)]


@pytest.mark.parametrize("margin", [0.05, 0.10])
def test_gap_narrower_than_the_body_plus_margins_is_never_passable(margin: float) -> None:
    # the body is 0.50 m at its narrowest: anything below 0.50 + 2·margin cannot be crossed
    for gap in (0.45, 0.5 + 2 * margin - 0.01):
        ok, length = prove_passable(_barrier(gap), SPEC, BOX, margin)
        assert not ok, f"gap {gap:.3f} m proven passable with margin {margin}"
        assert math.isinf(length)


@pytest.mark.parametrize("margin", [0.05, 0.10])
def test_gap_with_room_to_spare_is_proven_passable(margin: float) -> None:
    # conservative by at most r·dθ/2 + res/√2 per side (~2.5 cm) plus the wall rasterisation: 0.10 m spare
    gap = 0.5 + 2 * margin + 0.10
    ok, length = prove_passable(_barrier(gap), SPEC, BOX, margin)
    assert ok
    assert 10.0 - 0.05 <= length < 11.0   # the straight 10 m line through the centred gap, give or take a cell


def test_a_gap_only_a_turned_body_fits_needs_the_turn() -> None:
    # 0.70 m gap: the body (0.70 long, 0.50 wide) fits only turned sideways; starting and ending facing north it
    # must rotate in the open before and after, which the heading dimension of the search allows
    ok, _ = prove_passable(_barrier(0.70), SPEC, BOX, 0.05)
    assert ok
    wide_body = FootprintBox(half_length=0.35, half_width=0.35)    # a 0.70 m square cannot fit at any heading
    ok, _ = prove_passable(_barrier(0.70), SPEC, wide_body, 0.05)
    assert not ok


def test_automaton_fill_and_smoothing() -> None:
    rng = np.random.default_rng(1)
    dense = post_field(rng, (50, 40), 0.35, iterations=0)
    assert 0.3 < dense.mean() < 0.4
    smoothed = post_field(np.random.default_rng(1), (50, 40), 0.35, iterations=2, survive=3)
    assert smoothed.mean() < dense.mean()     # lone posts and strands go


def test_generated_world_is_a_valid_scene_with_the_goal_ten_metres_up() -> None:
    from hal_panda_mobile.files import load_scene

    world = next(w for w in (generate(s, 0.25, survive=3) for s in range(20)) if w.passable)
    scene = load_scene(world.scene())
    assert math.isclose(scene.waypoints["goal"][1] - scene.start[1], 10.0)
    assert len(scene.boxes) == len(world.post_rects) > 0
    assert world.shortest >= 10.0 - 0.05
