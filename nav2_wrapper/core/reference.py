"""Reference planner: plain Dijkstra/A* over the same move model as the fast search, written to be checked by eye.

Why it is in the product and not in a test: the tests and the planner benchmark both compare the fast kernel
(``_search.astar``) against it, pair by pair, on cost and on path validity, and a navigation engineer can call
it to audit a plan. It shares no code with the fast kernel except the traversal table the planner builds.

The move model (the planner's, see ``_search``): entering a cell costs its factor ``table[cost]`` times the
step length (1 or √2); a blocked cell (factor inf) is entered at ``esc_cost`` when it lies within
``sqrt(esc_r2)`` cells of the start; a diagonal move never squeezes between two blocked orthogonal cells unless
it enters that disc. The search is a textbook A* on a binary heap (``heapq``) with the octile distance times
the cheapest factor as its consistent heuristic (``weight`` 0: Dijkstra), compiled by numba only because pure
Python takes seconds on a 2000×2000 map (``_astar.py_func`` is the same code uncompiled).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

SQRT2 = math.sqrt(2.0)


@dataclass
class ReferencePath:
    """The reference's answer: ``cost`` (inf when unreachable) and the (row, col) cells start..goal."""

    cost: float
    cells: NDArray[np.int64]


def factor_grid(costs: NDArray[np.uint8], table: NDArray[np.float64], start: tuple[int, int], esc_r2: float,
                esc_cost: float) -> NDArray[np.float64]:
    """Per-cell entry factor: ``table[cost]``, with the blocked cells of the start's escape disc at ``esc_cost``."""
    f = table[costs].astype(np.float64)
    f[escape_disc(costs.shape, start, esc_r2) & np.isinf(f)] = esc_cost
    return f


def escape_disc(shape: tuple[int, ...], start: tuple[int, int], esc_r2: float) -> NDArray[np.bool_]:
    """Cells within ``sqrt(esc_r2)`` of the start cell."""
    disc = np.zeros(shape[:2], bool)
    k = int(math.sqrt(max(esc_r2, 0.0)))
    r0, c0 = max(0, start[0] - k), max(0, start[1] - k)
    rr, cc = np.mgrid[r0:min(shape[0], start[0] + k + 1), c0:min(shape[1], start[1] + k + 1)]
    disc[r0:r0 + rr.shape[0], c0:c0 + rr.shape[1]] = (rr - start[0]) ** 2 + (cc - start[1]) ** 2 <= esc_r2
    return disc


def move_cost(factor: NDArray[np.float64], costs_blocked: NDArray[np.bool_], disc: NDArray[np.bool_],
              a: tuple[int, int], b: tuple[int, int]) -> float:
    """Cost of one move a -> b (8-neighbours) in the model above; inf when not allowed."""
    dr, dc = b[0] - a[0], b[1] - a[1]
    w = factor[b]
    if dr and dc:
        if costs_blocked[a[0], b[1]] and costs_blocked[b[0], a[1]] and not disc[b]:
            return math.inf
        return SQRT2 * w
    return float(w)


def path_cost(costs: NDArray[np.uint8], table: NDArray[np.float64], cells: NDArray[np.int64], esc_r2: float = 0.0,
              esc_cost: float = math.inf) -> float:
    """Cost of a path of 8-connected (row, col) cells, the first being the start; inf if a move is not allowed."""
    start = (int(cells[0][0]), int(cells[0][1]))
    factor = factor_grid(costs, table, start, esc_r2, esc_cost)
    disc = escape_disc(costs.shape, start, esc_r2)
    blocked = np.isinf(table[costs])
    total = 0.0
    for a, b in zip(cells[:-1], cells[1:], strict=True):
        if max(abs(int(b[0]) - int(a[0])), abs(int(b[1]) - int(a[1]))) != 1:
            return math.inf
        total += move_cost(factor, blocked, disc, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])))
    return total


def reference_plan(costs: NDArray[np.uint8], table: NDArray[np.float64], start: tuple[int, int],
                   goal: tuple[int, int], esc_r2: float = 0.0, esc_cost: float = math.inf,
                   weight: float = 1.0) -> ReferencePath:
    """Cheapest path from ``start`` to ``goal`` ((row, col) cells) in the planner's model (``weight`` 1: A*,
    0: Dijkstra; both optimal)."""
    factor = factor_grid(costs, table, start, esc_r2, esc_cost)
    disc = escape_disc(costs.shape, start, esc_r2)
    blocked = np.isinf(table[costs])
    h_scale = float(min(np.min(table), esc_cost)) * weight
    cost, parent = _astar(factor, blocked, disc, start[0], start[1], goal[0], goal[1], h_scale)
    if not math.isfinite(cost):
        return ReferencePath(math.inf, np.zeros((0, 2), np.int64))
    cols = costs.shape[1]
    out = [goal[0] * cols + goal[1]]
    while out[-1] != start[0] * cols + start[1]:
        out.append(int(parent[out[-1]]))
    cells = np.array(out[::-1], np.int64)
    return ReferencePath(cost, np.stack([cells // cols, cells % cols], axis=1))


@njit(cache=True)
def _astar(factor, blocked, disc, sr, sc, gr, gc, h_scale):  # pragma: no cover - compiled
    """Textbook A*: a heap of (f, cell), a closed flag, g and a parent per cell. Returns (cost, parent)."""
    rows, cols = factor.shape
    g = np.full(rows * cols, np.inf)
    parent = np.full(rows * cols, -1, np.int64)
    done = np.zeros(rows * cols, np.bool_)
    start, goal = sr * cols + sc, gr * cols + gc
    g[start] = 0.0
    heap = [(0.0, start)]
    while heap:
        _, cur = heapq.heappop(heap)
        if done[cur]:
            continue
        done[cur] = True
        if cur == goal:
            return g[cur], parent
        r, c = cur // cols, cur % cols
        for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1)):
            nr, nc = r + dr, c + dc
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            w = factor[nr, nc]
            if dr != 0 and dc != 0:
                if blocked[r, nc] and blocked[nr, c] and not disc[nr, nc]:
                    continue
                w *= SQRT2
            nb = nr * cols + nc
            if g[cur] + w < g[nb]:
                g[nb] = g[cur] + w
                parent[nb] = cur
                dy, dx = abs(nr - gr), abs(nc - gc)
                h = (dy + dx + (SQRT2 - 2.0) * min(dy, dx)) * h_scale
                heapq.heappush(heap, (g[nb] + h, nb))
    return np.inf, parent
