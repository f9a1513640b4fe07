"""Chained variant of the cost-optimal bucket search (``_search.astar_buckets``): a cost-0 cell in open space is
expanded by scanning, and the cells a scan passes are expanded on the spot, not through the queue.

Why: on the bench maps 70-80 % of the cells every octile A* must expand are cost-0 cells whose whole 3×3
neighbourhood is cost 0 (``bench/planner_bounds.py --blocks``, ``uniform_share``). At a cost-0 cell the bucket
kernel's move pruning (``_search._expand_after``) leaves exactly the jump-point successors whenever the
neighbours it weighs cost 0 too: after a straight arrival with both side neighbours cost 0 only the move ahead
(the sides are cheaper by the predecessor's diagonal, the forward diagonals at no more cost diagonal-first
through a side, whatever they cost), after a diagonal arrival with the two orthogonal neighbours behind cost 0
the diagonal and its two straight components. Such a cell (``scannable``) is expanded by a scan: walk straight
ahead (or along the diagonal, and from every cell passed along its two components), giving each cell passed
its g, the move that reached it and the closed bit, as the bucket kernel would when expanding it. A scan stops
at a cell that already has an equal or better g in this plan (that label's expansion covers it) or that it
cannot enter, and files the cell it ends on into the queue like any relaxation: the first one that is not
passable in the same way (it is expanded with the bucket kernel's pruning), the goal, one past f = the scanning
cell's f + ``reach`` (a scan away from the goal would otherwise run where the search never gets) or ``cap``
steps out. The successor function and the records are the bucket kernel's, so the path is walked back along g
by ``_search.backtrack``; only the order of expansion changes (a scanned cell may be expanded before its
bucket: like a cell expanded early inside a bucket, a better g later re-files it). Costs are read on the fly
(three loads per straight step), so nothing per costmap is cached or invalidated.

Unlike jump point search proper, passed cells get records: scans from neighbouring origins overlap heavily on
these maps, and the records let a scan stop where an earlier one already went with a better g (a record-free
variant with a parent index per filed cell measured 0.98-1.19 × the bucket kernel's time, see the README).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._search import (
    _NEED_ROOM,
    SQRT2,
    _close,
    _expand_border,
    _expand_interior,
    _file,
    _interior,
    _mdc,
    _mdr,
    _move_cost,
    _octile,
    _past_goal,
    _prefetch,
    _relax,
    _room,
    _u,
    open_buckets,
)

_FOUND = 1
_EXHAUSTED = 0
AHEAD = 4   # cells ahead of a scan whose record is prefetched


def chain_rise(cap: int, reach: float, wmax: float, h_scale: float) -> float:
    """Largest f increase of one filed entry over the popped cell whose scan filed it (sizes the bucket ring):
    scans stop once past f + ``reach``, so one step beyond that (a step into a cell of factor at most ``wmax``
    raises f by at most √2·(wmax + h_scale)), and they are at most ``cap`` diagonal plus ``cap`` straight steps."""
    return min((SQRT2 + 1.0) * cap * (wmax + h_scale), reach + SQRT2 * (wmax + h_scale))


@njit(cache=True, inline="always")
def _zero3(flat, a, p):
    """Cells a − p, a, a + p all cost 0."""
    return flat[_u(a - p)] == 0 and flat[_u(a)] == 0 and flat[_u(a + p)] == 0


@njit(cache=True, inline="always")
def _limit(r, c, dr, dc, rows, cols, cap):
    """Steps a scan from (r, c) in (dr, dc) may take so that every cell it may pass (all but the last it reaches)
    stays one cell inside the map edge: the pass test reads its neighbours."""
    n = cap
    if dr > 0:
        n = min(n, rows - 1 - r)
    elif dr < 0:
        n = min(n, r)
    if dc > 0:
        n = min(n, cols - 1 - c)
    elif dc < 0:
        n = min(n, c)
    return n


@njit(cache=True, inline="always")
def _pass(rec, recg, y, g, seen, k):
    """Cell ``y`` passed by a scan at g ``g`` arriving by move ``k``: True (and y closed with that label) when
    that improves its g, False when an earlier label is as good (the scan stops)."""
    if rec[_u(2 * y)] >= seen and not g < np.float64(recg[_u(2 * y + 1)]):
        return False
    rec[_u(2 * y)] = seen | (k << 1) | 1
    recg[_u(2 * y + 1)] = g
    return True


@njit(cache=True, inline="always")
def _straight(flat, table, rec, recg, y, r, c, g, k, n, goal, seen, gr, gc, h_scale, inv, cb, mask, buckets, counts,
              flim, cols, esc):
    """Scan from expanded cell ``y`` = (r, c) at g ``g`` along straight move ``k``, at most ``n`` steps (see the
    module doc). A cell passes when it and its two side neighbours cost 0: the bucket kernel's pruning then leaves
    only the move ahead whatever the cells ahead and behind cost. ``esc`` = (start row, start col, escape radius²,
    escape cost) for ``_move_cost``. Returns (entries filed, that bucket's length, cells passed)."""
    dr, dc = _mdr(k), _mdc(k)
    o = dr * cols + dc
    p = cols if dr == 0 else 1          # to the side neighbours
    s = 0
    while True:
        step = _move_cost(flat, table, cols, r, c, r + dr, c + dc, esc[0], esc[1], esc[2], esc[3])
        if step == np.inf:
            return 0, 0, s              # blocked ahead: the scanned cell has no successor
        y += o
        r += dr
        c += dc
        g += step
        s += 1
        if s < n and y != goal and _zero3(flat, y, p) and g + h_scale * _octile(r, c, gr, gc) <= flim:
            _prefetch(rec, 2 * (y + AHEAD * o))     # a column scan meets a new cache line every step
            if not _pass(rec, recg, y, g, seen, k):
                return 0, 0, s - 1
            continue
        key = _relax(rec, recg, k, y, g, seen, r, c, gr, gc, h_scale, inv, cb, mask)
        if key < 0:
            return 0, 0, s - 1
        return 1, _file(buckets, counts, key, y), s - 1


@njit(cache=True, inline="always")
def scannable(flat, cur, r, c, d, rows, cols):
    """Whether cell ``cur`` = (r, c) reached by move ``d`` (0-7) is expanded by a scan: it costs 0, lies off the
    map edge, and after a straight arrival its two side neighbours cost 0 (only the move ahead survives the
    pruning), after a diagonal one the two orthogonal neighbours behind it do (only the diagonal and its two
    components survive)."""
    if not (0 < r < rows - 1 and 0 < c < cols - 1) or flat[_u(cur)] != 0:
        return False
    dr, dc = _mdr(d), _mdc(d)
    if d < 4:
        p = cols if dr == 0 else 1
        return flat[_u(cur - p)] == 0 and flat[_u(cur + p)] == 0
    return flat[_u(cur - dr * cols)] == 0 and flat[_u(cur - dc)] == 0


@njit(cache=True, inline="always")
def _scan(flat, table, rows, cols, cur, r, c, d, gcur, goal, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
          buckets, counts, cap, flim, esc):
    """Expand cell ``cur`` reached by move ``d`` (0-7), ``scannable``, by scanning (see the module doc). Returns
    (entries filed, the longest bucket after, cells passed)."""
    dr, dc = _mdr(d), _mdc(d)
    if d < 4:
        return _straight(flat, table, rec, recg, cur, r, c, gcur, d, _limit(r, c, dr, dc, rows, cols, cap), goal,
                         seen, gr, gc, h_scale, inv, cb, mask, buckets, counts, flim, cols, esc)
    kv = 1 if dr > 0 else 0
    kh = 3 if dc > 0 else 2
    nd = _limit(r, c, dr, dc, rows, cols, cap)
    z, zr, zc, gz = cur, r, c, gcur
    added = most = passed = 0
    i = 0
    while True:
        # z is expanded: its successors are the two straight components and the diagonal
        a, m, s = _straight(flat, table, rec, recg, z, zr, zc, gz, kv, _limit(zr, zc, dr, 0, rows, cols, cap), goal,
                            seen, gr, gc, h_scale, inv, cb, mask, buckets, counts, flim, cols, esc)
        added += a
        most = max(most, m)
        passed += s
        a, m, s = _straight(flat, table, rec, recg, z, zr, zc, gz, kh, _limit(zr, zc, 0, dc, rows, cols, cap), goal,
                            seen, gr, gc, h_scale, inv, cb, mask, buckets, counts, flim, cols, esc)
        added += a
        most = max(most, m)
        passed += s
        i += 1
        step = _move_cost(flat, table, cols, zr, zc, zr + dr, zc + dc, esc[0], esc[1], esc[2], esc[3])
        if step == np.inf:
            return added, most, passed
        z, zr, zc, gz = z + dr * cols + dc, zr + dr, zc + dc, gz + step
        if (i >= nd or z == goal or flat[_u(z)] != 0 or flat[_u(z - dr * cols)] != 0 or flat[_u(z - dc)] != 0
                or gz + h_scale * _octile(zr, zc, gr, gc) > flim):
            break
        _prefetch(rec, 2 * (z + AHEAD * (dr * cols + dc)))
        if not _pass(rec, recg, z, gz, seen, d):
            return added, most, passed
        passed += 1
    key = _relax(rec, recg, d, z, gz, seen, zr, zc, gr, gc, h_scale, inv, cb, mask)
    if key >= 0:
        added += 1
        most = max(most, _file(buckets, counts, key, z))
    return added, most, passed


@njit(cache=True)
def astar_chains(costs, table, start, goal, rec, stamp, esc_r2, esc_cost, h_scale, delta, nbuckets, cap, reach):
    """``_search.astar_buckets`` with ``scannable`` cells expanded by scans (see the module doc). Same record
    layout, return value (plus the cells scans passed) and failure state (every cell reachable from the start
    closed). ``nbuckets`` must cover ``chain_rise(cap, reach, ...)``."""
    rows, cols = costs.shape
    # the loop's state between calls: current bucket, open entries, fullest bucket, expansions, cells scanned
    recg, seen, buckets, counts, state, drs, dcs = open_buckets(costs, start, goal, rec, stamp, h_scale, delta,
                                                                 nbuckets, 5)
    burst = 2 * cap + 8        # the most entries one expansion can file
    while True:
        status = _expand_chains(costs.ravel(), rows, cols, table, goal, rec, recg, seen, esc_r2, esc_cost, h_scale,
                                delta, start, buckets, counts, state, drs, dcs, cap, reach, burst)
        if status != _NEED_ROOM:
            return status == _FOUND, state[3], state[4]
        buckets = _room(buckets, state[2] + burst)


@njit(cache=True)
def _expand_chains(flat, rows, cols, table, goal, rec, recg, seen, esc_r2, esc_cost, h_scale, delta,
                   start, buckets, counts, state, drs, dcs, cap, reach, burst):
    """``_search._expand`` plus the scan branch: a popped ``scannable`` cell (not the goal, reached by a move) is
    expanded by ``_scan``, any other cell as there."""
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    inv = 1.0 / delta
    mask = buckets.shape[0] - 1
    room = buckets.shape[1] - burst
    cb, pending, fullest, expansions, scanned = state[0], state[1], state[2], state[3], state[4]
    far = int(np.sqrt(max(esc_r2, 0.0))) + 2
    esc = (sr, sc, esc_r2, esc_cost)
    while pending > 0:
        b = cb & mask
        while counts[b] > 0:
            if fullest > room:
                state[0], state[1], state[2], state[3], state[4] = cb, pending, fullest, expansions, scanned
                return _NEED_ROOM
            counts[b] -= 1
            cur = buckets[_u(b), _u(counts[b])]
            pending -= 1
            r = cur // cols
            c = cur - r * cols
            gcur = np.float64(recg[_u(2 * cur + 1)])
            fcur = gcur + h_scale * _octile(r, c, gr, gc)
            d = _close(rec, recg, cur, seen, goal, fcur)
            if d < 0:
                continue
            expansions += 1
            if d < 8 and cur != goal and scannable(flat, cur, r, c, d, rows, cols):
                added, most, passed = _scan(flat, table, rows, cols, cur, r, c, d, gcur, goal, rec, recg, seen, gr, gc,
                                            h_scale, inv, cb, mask, buckets, counts, cap, fcur + reach, esc)
                scanned += passed
            elif _interior(r, c, rows, cols, sr, sc, far):
                added, most = _expand_interior(d, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                               h_scale, inv, cb, mask, buckets, counts)
            else:
                added, most = _expand_border(flat, rows, cols, table, r, c, gcur, rec, recg, seen, sr, sc, gr, gc,
                                             esc_r2, esc_cost, h_scale, inv, cb, mask, buckets, counts, drs, dcs)
            pending += added
            fullest = max(fullest, most)
        if _past_goal(rec, recg, seen, goal, (cb + 1) * delta):
            state[3], state[4] = expansions, scanned
            return _FOUND
        cb += 1
    state[3], state[4] = expansions, scanned
    return _EXHAUSTED
