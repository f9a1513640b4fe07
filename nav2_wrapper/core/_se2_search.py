"""numba kernels for the footprint-aware (x, y, heading) planner in ``se2_planner``.

Three loops that are too slow in numpy: the per-heading collision grid (lethal cells dilated by the rotated
footprint), the 2D cost-to-go used as the search's heuristic, and the lattice A* itself. Kept apart from the
2D planner's ``_search`` module (a different state space and a simpler binary heap: the SE(2) search runs
only as a fallback, so clarity beats the last factor of two). Compiled with cache=True.

A state is the flat index ``(bin * rows + row) * cols + col`` of a window of the costmap.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numba import njit

SQRT2 = math.sqrt(2.0)


@njit(cache=True)
def dilate_rows(lethal, pad, lo, hi, decided, out):  # pragma: no cover - compiled
    """``out[b, r, c]`` (bins × rows × cols) = whether any lethal cell lies under kernel ``b`` centred at (r, c).

    ``lethal`` is the window padded by ``pad`` cells on every side; a kernel is convex, so its row ``di``
    (−pad … pad) is one interval of column offsets ``lo[b, di + pad] … hi[b, di + pad]`` (empty if lo > hi), and
    each interval test is one difference of a row prefix sum (computed once for all bins): the cost is
    bins × rows × cols × kernel rows, whatever the number of obstacles. Cells where ``decided[r, c]`` is 0 (free
    at every heading) or 1 (blocked at every heading) are filled without the test; 2 means test."""
    bins, rows, cols = out.shape
    prow, pcol = lethal.shape
    pre = np.zeros((prow, pcol + 1), np.int32)
    for r in range(prow):
        acc = 0
        for c in range(pcol):
            acc += lethal[r, c]
            pre[r, c + 1] = acc
    for b in range(bins):
        for r in range(rows):
            for c in range(cols):
                if decided[r, c] != 2:
                    out[b, r, c] = decided[r, c] == 1
                    continue
                hit = False
                for k in range(2 * pad + 1):
                    a, e = lo[b, k], hi[b, k]
                    if a > e:
                        continue
                    if pre[r + k, c + pad + e + 1] - pre[r + k, c + pad + a] > 0:
                        hit = True
                        break
                out[b, r, c] = hit


@njit(cache=True)
def cost_to_go(passable, factor, goals, out):  # pragma: no cover - compiled
    """Dijkstra from the goal cells over ``passable`` cells, 8-connected: ``out`` is the cheapest cost of
    reaching a goal, where a step costs its length (cells) times ``factor`` of the cell it enters.

    With ``passable`` = free at some heading it never exceeds the SE(2) cost to go (every lattice path projects
    onto such cells with the same translation costs), so it is an admissible and consistent heuristic."""
    rows, cols = passable.shape
    out[:, :] = np.inf
    heap = [(0.0, np.int64(0))]
    heap.pop()
    for g in goals:
        out[g // cols, g % cols] = 0.0
        heapq.heappush(heap, (0.0, np.int64(g)))
    drs = (-1, -1, -1, 0, 0, 1, 1, 1)
    dcs = (-1, 0, 1, -1, 1, -1, 0, 1)
    while len(heap) > 0:
        d, v = heapq.heappop(heap)
        r, c = v // cols, v % cols
        if d > out[r, c]:
            continue
        fv = factor[r, c]      # the reverse step u → v enters v
        for k in range(8):
            nr, nc = r + drs[k], c + dcs[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols or not passable[nr, nc]:
                continue
            step = SQRT2 if drs[k] != 0 and dcs[k] != 0 else 1.0
            nd = d + step * fv
            if nd < out[nr, nc]:
                out[nr, nc] = nd
                heapq.heappush(heap, (nd, np.int64(nr * cols + nc)))


@njit(cache=True)
def _less(hk, hv, i, j):  # pragma: no cover - compiled
    """Heap order: by key, then by state (what a heap of (key, state) tuples does)."""
    return hk[i] < hk[j] or (hk[i] == hk[j] and hv[i] < hv[j])


@njit(cache=True)
def _swap(hk, hv, i, j):  # pragma: no cover - compiled
    hk[i], hk[j] = hk[j], hk[i]
    hv[i], hv[j] = hv[j], hv[i]


@njit(cache=True)
def heap_push(hk, hv, n, key, val):  # pragma: no cover - compiled
    """Push onto the binary heap held in hk/hv[:n] (the caller made room); returns the new size."""
    hk[n], hv[n] = key, val
    i = n
    while i > 0:
        p = (i - 1) // 2
        if not _less(hk, hv, i, p):
            break
        _swap(hk, hv, i, p)
        i = p
    return n + 1


@njit(cache=True)
def heap_pop(hk, hv, n):  # pragma: no cover - compiled
    """Remove the least entry of hk/hv[:n]; returns (its state, the new size)."""
    top = hv[0]
    n -= 1
    hk[0], hv[0] = hk[n], hv[n]
    i = 0
    while True:
        a, b, m = 2 * i + 1, 2 * i + 2, i
        if a < n and _less(hk, hv, a, m):
            m = a
        if b < n and _less(hk, hv, b, m):
            m = b
        if m == i:
            break
        _swap(hk, hv, i, m)
        i = m
    return top, n


@njit(cache=True)
def lattice_astar(blocked, factor, h, start, goal_mask, rot_cost, weight, escape_r2, escape_factor, budget,
                  g, parent, closed, hk, hv, size):  # pragma: no cover - compiled
    """A* over (bin, row, col), resumable: runs until a goal, an empty queue or ``budget`` expansions, and
    keeps its whole state in the arrays passed in, so the next call carries on where this one stopped.
    Returns (goal state, or −1: no route, −2: budget spent, −3: the heap arrays need room; expansions).

    The caller initialises ``g`` = inf, ``parent`` = −1, ``closed`` = False, pushes the start (``size[0]`` is
    the heap's size). Moves: the 8 translations within a bin (cost = length × ``factor`` of the entered cell)
    and a turn to the neighbouring bin (cost ``rot_cost``; the bins wrap at a half turn), both allowed only
    into states that are not ``blocked``. Within ``escape_r2`` (cells²) of the start, blocked states may be
    entered at ``escape_factor`` per cell so a body already touching a noise speckle can leave."""
    bins, rows, cols = blocked.shape
    plane = rows * cols
    sr, sc = (start % plane) // cols, start % cols
    hw = weight * (1.0 + 1e-6)       # a hair above weight: on equal f, the state nearer the goal pops first
    drs = (-1, -1, -1, 0, 0, 1, 1, 1)
    dcs = (-1, 0, 1, -1, 1, -1, 0, 1)
    n = size[0]
    expansions = 0
    while n > 0:
        if n + 10 > len(hk):
            size[0] = n
            return -3, expansions
        if expansions >= budget:
            size[0] = n
            return -2, expansions
        s, n = heap_pop(hk, hv, n)
        if closed[s]:
            continue
        closed[s] = True
        expansions += 1
        b, rem = s // plane, s % plane
        r, c = rem // cols, rem % cols
        if goal_mask[r, c]:
            size[0] = n
            return s, expansions
        gs = g[s]
        for k in range(10):
            if k < 8:
                nb, nr, nc = b, r + drs[k], c + dcs[k]
                if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                    continue
                step = SQRT2 if drs[k] != 0 and dcs[k] != 0 else 1.0
                cost = step * factor[nr, nc]
            else:
                nb, nr, nc = (b + (1 if k == 8 else bins - 1)) % bins, r, c
                cost = rot_cost
            if blocked[nb, nr, nc]:
                dr, dc = nr - sr, nc - sc
                if dr * dr + dc * dc > escape_r2:
                    continue
                cost = cost * escape_factor
            if not math.isfinite(cost):
                continue
            t = (nb * rows + nr) * cols + nc
            ng = gs + cost
            if ng < g[t] and not closed[t]:
                g[t] = ng
                parent[t] = s
                hv_ = h[nr, nc]
                if math.isfinite(hv_):
                    n = heap_push(hk, hv, n, ng + hw * hv_, np.int64(t))
    size[0] = n
    return -1, expansions
