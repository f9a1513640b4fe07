"""The planner benchmark's maps and start/goal pairs, shared by ``bench/planner_bench.py``,
``bench/planner_bounds.py`` and tests, so none of them edits ``sys.path`` to reach another's helpers.

Maps are square grids at ``RES`` m with random boxes and discs up to an obstacle density; pairs are drawn from
the largest free component of a costmap at a distance range (``SETTINGS``: "near" ≥ 3 m, "far" 60-95 m).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from nav2_wrapper.core import INSCRIBED, Costmap

Cell = tuple[int, int]
RES = 0.05
SETTINGS = {"near": (3.0, math.inf), "far": (60.0, 95.0)}   # start-goal distance ranges, m


def make_map(size: int, density: float, rng: np.random.Generator) -> np.ndarray:
    occ = np.zeros((size, size), bool)
    yy, xx = np.mgrid[-20:21, -20:21]
    while occ.mean() < density:
        for _ in range(max(1, int((density - occ.mean()) * size * size / 600))):
            r, c = rng.integers(0, size, 2)
            if rng.random() < 0.7:
                h, w = rng.integers(4, 41, 2)
                occ[r:r + h, c:c + w] = True
            else:
                rad = int(rng.integers(3, 21))
                disc = (yy ** 2 + xx ** 2) <= rad * rad
                r0, c0 = max(0, r - 20), max(0, c - 20)
                sub = disc[r0 - (r - 20):, c0 - (c - 20):][: size - r0, : size - c0]
                occ[r0:r0 + sub.shape[0], c0:c0 + sub.shape[1]] |= sub
    return np.where(occ, 100, 0).astype(np.int8)


def pick_pairs(cm: Costmap, n: int, rng: np.random.Generator, lo: float, hi: float) -> list[tuple[Cell, Cell]]:
    """n random (start, goal) cells of the largest free component, lo..hi m apart."""
    free = cm.costs < INSCRIBED
    lab, _ = ndimage.label(free)   # 4-connected: the planner forbids diagonal squeezes between blocked cells
    big = np.bincount(lab.ravel())[1:].argmax() + 1
    cells = np.argwhere(lab == big)
    pairs: list[tuple[Cell, Cell]] = []
    while len(pairs) < n:
        a, b = cells[rng.integers(len(cells))], cells[rng.integers(len(cells))]
        if lo <= math.hypot(*(a - b)) * RES <= hi:
            pairs.append(((int(a[0]), int(a[1])), (int(b[0]), int(b[1]))))
    return pairs


def world(cm: Costmap, cell: Cell) -> tuple[float, float]:
    x, y = cm.cell_to_world(cell[1], cell[0])
    return float(x), float(y)
