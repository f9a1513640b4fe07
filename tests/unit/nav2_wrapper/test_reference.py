"""The reference planner agrees with itself as Dijkstra and as A*, and its paths cost what it reports."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nav2_wrapper.core.costs import LETHAL, MAX_NON_OBSTACLE
from nav2_wrapper.core.reference import path_cost, reference_plan


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_astar_equals_dijkstra_and_the_path_costs_the_cost(seed: int) -> None:
    rng = np.random.default_rng(seed)
    costs = rng.integers(0, MAX_NON_OBSTACLE + 1, (30, 40)).astype(np.uint8)
    costs[rng.random(costs.shape) < 0.2] = LETHAL
    table = 1.0 + 2.0 * np.arange(256) / MAX_NON_OBSTACLE
    table[253:255] = np.inf
    free = np.argwhere(np.isfinite(table[costs]))
    found = 0
    for _ in range(20):
        a, b = (tuple(int(v) for v in free[rng.integers(len(free))]) for _ in range(2))
        astar = reference_plan(costs, table, a, b, 4.0, 5.0)
        dijkstra = reference_plan(costs, table, a, b, 4.0, 5.0, weight=0.0)
        assert astar.cost == pytest.approx(dijkstra.cost, rel=1e-12) or astar.cost == dijkstra.cost == math.inf
        if math.isfinite(astar.cost):
            found += 1
            assert tuple(astar.cells[0]) == a
            assert tuple(astar.cells[-1]) == b
            assert path_cost(costs, table, astar.cells, 4.0, 5.0) == pytest.approx(astar.cost, rel=1e-12)
    assert found >= 10


def test_a_diagonal_squeeze_is_refused_and_a_path_through_a_wall_is_priced_inf() -> None:
    costs = np.zeros((3, 3), np.uint8)
    costs[0, 1] = costs[1, 0] = LETHAL
    table = np.ones(256)
    table[253:255] = np.inf
    assert reference_plan(costs, table, (0, 0), (2, 2)).cost == math.inf     # (0,0) is walled in
    assert path_cost(costs, table, np.array([[0, 0], [1, 1]])) == math.inf
    assert path_cost(costs, table, np.array([[2, 2], [1, 1]])) == pytest.approx(math.sqrt(2.0))
