"""numba kernels for the global planner: cost-aware 8-connected A* and the line-of-sight shortcut pass.

Kept apart from planner.py so the Python-level logic stays readable; compiled with cache=True so only
the first process on a machine pays the compile time.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SQRT2 = math.sqrt(2.0)


@njit(cache=True, inline="always")
def _heap_push(keys, vals, n, k, v):
    i = n
    keys[i] = k
    vals[i] = v
    while i > 0:
        p = (i - 1) >> 1
        if keys[p] <= keys[i]:
            break
        keys[p], keys[i] = keys[i], keys[p]
        vals[p], vals[i] = vals[i], vals[p]
        i = p
    return n + 1


@njit(cache=True, inline="always")
def _heap_pop(keys, vals, n):
    v = vals[0]
    n -= 1
    keys[0] = keys[n]
    vals[0] = vals[n]
    i = 0
    while True:
        lc = 2 * i + 1
        if lc >= n:
            break
        rc = lc + 1
        m = lc if (rc >= n or keys[lc] <= keys[rc]) else rc
        if keys[i] <= keys[m]:
            break
        keys[m], keys[i] = keys[i], keys[m]
        vals[m], vals[i] = vals[i], vals[m]
        i = m
    return v, n


@njit(cache=True)
def astar(costs, table, start, goal, g, parent, state, stamp, esc_r2, esc_cost, h_weight):
    """A* from cell ``start`` to ``goal`` (flat indices) on ``costs`` (uint8, rows×cols).

    ``table[c]`` is the traversal factor of cost c (inf = blocked). Cells within sqrt(esc_r2) cells of the
    start are passable at ``esc_cost`` even when blocked, so a robot whose centre sits in the inscribed band
    can leave it. ``state`` holds 2·stamp (seen) or 2·stamp+1 (closed) for this search, so the buffers are
    reused without clearing (compact buffers: the search is memory-bound on large maps).
    Returns (found, expansions).
    """
    rows, cols = costs.shape
    flat = costs.ravel()
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    cap = 1 << 16
    keys = np.empty(cap, np.float64)
    vals = np.empty(cap, np.int64)
    n = 0
    seen = 2 * stamp
    done = seen + 1
    g[start] = 0.0
    parent[start] = -1
    state[start] = seen
    n = _heap_push(keys, vals, n, 0.0, start)
    drs = np.array([-1, 1, 0, 0, -1, -1, 1, 1])
    dcs = np.array([0, 0, -1, 1, -1, 1, -1, 1])
    expansions = 0
    while n > 0:
        cur, n = _heap_pop(keys, vals, n)
        if state[cur] == done:
            continue
        state[cur] = done
        expansions += 1
        if cur == goal:
            return True, expansions
        r, c = cur // cols, cur % cols
        gcur = g[cur]
        for k in range(8):
            nr, nc = r + drs[k], c + dcs[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            nb = nr * cols + nc
            st = state[nb]
            if st == done:
                continue
            f = table[flat[nb]]
            if f == np.inf:
                if (nr - sr) * (nr - sr) + (nc - sc) * (nc - sc) > esc_r2:
                    continue
                f = esc_cost
            if k >= 4:
                # no diagonal squeeze between two blocked orthogonal neighbours
                if table[flat[r * cols + nc]] == np.inf and table[flat[nr * cols + c]] == np.inf:
                    if (nr - sr) * (nr - sr) + (nc - sc) * (nc - sc) > esc_r2:
                        continue
                step = SQRT2 * f
            else:
                step = f
            ng = gcur + step
            if st != seen or ng < g[nb]:
                state[nb] = seen
                g[nb] = ng
                parent[nb] = cur
                dr = abs(nr - gr)
                dc = abs(nc - gc)
                h = (dr + dc) + (SQRT2 - 2.0) * min(dr, dc)
                if n >= cap:
                    cap *= 2
                    nk = np.empty(cap, np.float64)
                    nv = np.empty(cap, np.int64)
                    nk[:n] = keys[:n]
                    nv[:n] = vals[:n]
                    keys, vals = nk, nv
                n = _heap_push(keys, vals, n, ng + h_weight * h, nb)
    return False, expansions


@njit(cache=True)
def backtrack(parent, goal):
    """Flat cell indices from the start to ``goal`` following ``parent``."""
    n = 0
    cur = goal
    while cur != -1:
        n += 1
        cur = parent[cur]
    out = np.empty(n, np.int64)
    cur = goal
    for i in range(n - 1, -1, -1):
        out[i] = cur
        cur = parent[cur]
    return out


@njit(cache=True)
def segment_cost(costs, table, r0, c0, r1, c1):
    """Cost-weighted length of the straight segment between two cell centres, visiting every cell it touches
    (supercover: at exact corner crossings both side cells count), the start cell excluded as in A*'s g.
    inf if any touched cell is blocked."""
    cols = costs.shape[1]
    flat = costs.ravel()
    dx = float(c1 - c0)
    dy = float(r1 - r0)
    length = math.sqrt(dx * dx + dy * dy)
    stepx = 1 if dx > 0 else -1
    stepy = 1 if dy > 0 else -1
    tdx = abs(1.0 / dx) if dx != 0 else np.inf
    tdy = abs(1.0 / dy) if dy != 0 else np.inf
    tmx = 0.5 * tdx
    tmy = 0.5 * tdy
    c, r = c0, r0
    total = 0.0
    count = 0
    while True:
        if c != c0 or r != r0:
            f = table[flat[r * cols + c]]
            if f == np.inf:
                return np.inf
            total += f
        count += 1
        if c == c1 and r == r1:
            break
        if abs(tmx - tmy) < 1e-9:
            if table[flat[r * cols + c + stepx]] == np.inf or table[flat[(r + stepy) * cols + c]] == np.inf:
                return np.inf
            c += stepx
            r += stepy
            tmx += tdx
            tmy += tdy
        elif tmx < tmy:
            c += stepx
            tmx += tdx
        else:
            r += stepy
            tmy += tdy
    return length * total / max(count - 1, 1)


@njit(cache=True)
def shortcut(costs, table, path, gvals, slack):
    """Theta*-style post-pass: from each kept vertex jump to the farthest later vertex whose straight segment
    is collision-free and no costlier than the sub-path it replaces. Returns indices of kept vertices."""
    cols = costs.shape[1]
    n = path.shape[0]
    keep = np.empty(n, np.int64)
    m = 0
    i = 0
    keep[m] = 0
    m += 1
    while i < n - 1:
        best = i + 1
        r0, c0 = path[i] // cols, path[i] % cols
        for j in range(i + 2, n):
            r1, c1 = path[j] // cols, path[j] % cols
            sc = segment_cost(costs, table, r0, c0, r1, c1)
            if sc == np.inf or sc > (gvals[j] - gvals[i]) * (1.0 + slack) + 1e-9:
                break
            best = j
        keep[m] = best
        m += 1
        i = best
    return keep[:m]
