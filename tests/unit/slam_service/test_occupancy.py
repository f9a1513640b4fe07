"""Log-odds grid: free along rays, occupied at hits, unknown elsewhere; grows without losing data."""

from __future__ import annotations

import numpy as np

from slam_service.core import LogOddsGrid


def _cell(grid, x: float, y: float) -> int:
    m = grid.to_gridmap()
    c, r = m.world_to_cell(x, y)
    return int(m.data[r, c])


def test_free_along_rays_occupied_at_hits() -> None:
    g = LogOddsGrid(0.05)
    ang = np.linspace(-0.3, 0.3, 61)
    hits = np.stack([2.0 * np.ones_like(ang), 2.0 * np.tan(ang)], axis=1)  # a wall at x = 2.0..2.05
    hits[:, 0] += 0.01
    for _ in range(3):
        g.integrate(np.array([0.0, 0.0]), hits)
    assert _cell(g, 2.01, 0.0) == 100
    assert _cell(g, 2.01, 0.5) == 100
    for x in (0.1, 0.7, 1.3, 1.9):
        assert _cell(g, x, 0.0) == 0, x
    assert _cell(g, 2.5, 0.0) == -1  # behind the wall: never observed
    assert _cell(g, 0.5, 1.5) == -1  # outside the beams' fan


def test_one_grazing_miss_does_not_erase_a_wall() -> None:
    g = LogOddsGrid(0.05)
    g.integrate(np.array([0.0, 0.0]), np.array([[1.02, 0.0]]))
    g.integrate(np.array([0.0, 0.0]), np.array([[1.02, 0.0]]))
    g.integrate(np.array([0.0, 0.0]), np.array([[2.02, 0.0]]))  # one ray passes through the cell
    assert _cell(g, 1.02, 0.0) == 100


def test_grid_grows_in_chunks_and_keeps_content() -> None:
    g = LogOddsGrid(0.05, chunk=16)
    g.integrate(np.array([0.0, 0.0]), np.array([[0.52, 0.0]]))
    g.integrate(np.array([0.0, 0.0]), np.array([[0.52, 0.0]]))
    before = g.logodds.shape
    g.integrate(np.array([-5.0, -3.0]), np.array([[-7.02, -3.0]]))
    g.integrate(np.array([-5.0, -3.0]), np.array([[-7.02, -3.0]]))
    after = g.logodds.shape
    assert after[0] >= before[0]
    assert after[1] > before[1]
    assert g.logodds.shape[0] % 16 == 0
    assert g.logodds.shape[1] % 16 == 0
    assert _cell(g, 0.52, 0.0) == 100
    assert _cell(g, -7.02, -3.0) == 100
    assert _cell(g, -6.0, -3.0) == 0
