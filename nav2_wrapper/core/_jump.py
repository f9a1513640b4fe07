"""Jumping variant of the cost-optimal bucket search (``_search.astar_buckets``): in regions of uniform cost 0,
straight and diagonal scans replace queue entries (jump-point style), elsewhere it is the same kernel.

Why: on the bench maps 70-80 % of the cells every octile A* must expand are cost-0 cells whose whole 3×3
neighbourhood is cost 0 (``bench/planner_bounds.py --blocks``, ``uniform_share``). Around such a cell the
bucket kernel's move pruning (``_search._expand_after``) leaves exactly the jump-point successors: after a
straight arrival only the move straight ahead, after a diagonal one the diagonal and its two straight
components (ties go diagonal-first, the canonical order the pruning already uses). A chain of cells with those
successors needs no queue: the scan walks it, and a cell is filed (given a record, g and a parent) only where
the pruning would leave other successors, i.e. at the first cell whose 3×3 neighbourhood is not all cost 0, at
the goal, at the map edge and every ``cap`` steps. So the successor function is the bucket kernel's; only
the cells passed over keep no record (a scanned cell may be passed by several scans, each its own label).

Filed cells carry ``16 + move`` in their state word (``_search.STATE_SHIFT``) and ``parent`` holds the filed
cell whose scan reached them; the path between is diagonal steps first, then straight ones, so
``backtrack_jumps`` redraws it cell by cell. Cells filed by ordinary relaxations keep the move 0-7 and are walked
back along g as in ``_search.backtrack``. Uniformity is tested on the fly from the costs (three loads per
straight step: the new row or column of the 3×3), so nothing per costmap has to be cached or invalidated.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._search import (
    _NEED_ROOM,
    SQRT2,
    STATE_SHIFT,
    STRAIGHT_TOL,
    _close,
    _expand_after,
    _expand_border,
    _file,
    _interior,
    _mdc,
    _mdr,
    _move_cost,
    _neighbour,
    _octile,
    _past_goal,
    _relax,
    _room,
    _u,
)

JUMP = 16   # added to the move in a state word whose g was set by a scan (the path back uses ``parent``)
_FOUND = 1
_EXHAUSTED = 0


def jump_rise(cap: int, reach: float, w0: float, h_scale: float) -> float:
    """Largest f increase of one filed entry over its parent (sizes the bucket ring): scans stop once past f +
    ``reach``, so one step beyond that (a step of factor ``w0`` raises f by at most √2·(w0 + h_scale)), and
    they are at most ``cap`` diagonal plus ``cap`` straight steps long."""
    return min((SQRT2 + 1.0) * cap, reach + SQRT2) * (w0 + h_scale)


@njit(cache=True, inline="always")
def _zero3(flat, a, p):
    """Cells a − p, a, a + p all cost 0."""
    return flat[_u(a - p)] == 0 and flat[_u(a)] == 0 and flat[_u(a + p)] == 0


@njit(cache=True, inline="always")
def _uniform(flat, y, cols):
    """The 3×3 block around ``y`` is all cost 0 (``y`` at least one cell from the map edge)."""
    return _zero3(flat, y - cols, 1) and _zero3(flat, y, 1) and _zero3(flat, y + cols, 1)


@njit(cache=True, inline="always")
def _limit(r, c, dr, dc, rows, cols, cap):
    """Steps a scan from (r, c) in (dr, dc) may take so that every cell it tests for uniformity (all but the
    last it reaches) stays one cell inside the map edge: the test reads the 3×3 around it."""
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
def _run(flat, y, o, p, n, goal, g0, w0, r, c, dr, dc, gr, gc, h_scale, flim):
    """Steps (1..n) a straight scan from uniform cell ``y`` = (r, c) at g ``g0`` along flat offset ``o`` = (dr, dc)
    takes to the first cell that is to be filed: the goal, a cell whose 3×3 block is not all cost 0 (its new
    line, ``p`` the perpendicular offset, has a non-zero cell), a cell whose f exceeds ``flim``, or the n-th."""
    s = 1
    while s < n:
        y1 = y + s * o
        if y1 == goal or not _zero3(flat, y1 + o, p):
            return s
        if g0 + s * w0 + h_scale * _octile(r + s * dr, c + s * dc, gr, gc) > flim:
            return s
        s += 1
    return n


@njit(cache=True, inline="always")
def _jump_to(rec, recg, parent, k, nb, ng, origin, seen, nr, nc, goal, gr, gc, h_scale, inv, cb, mask, buckets,
             counts):
    """File cell ``nb`` = (nr, nc) reached from filed cell ``origin`` by a scan ending in move ``k`` at g =
    ``ng``, if that improves its g. Returns (entries filed, that bucket's length)."""
    if rec[_u(2 * nb)] >= seen and not ng < np.float64(recg[_u(2 * nb + 1)]):
        return 0, 0
    if nb != goal and _past_goal(rec, recg, seen, goal, ng + h_scale * _octile(nr, nc, gr, gc)):
        return 0, 0             # no cheaper path to the goal through it (popped, it would be closed unexpanded)
    parent[_u(nb)] = origin
    key = _relax(rec, recg, JUMP + k, nb, ng, seen, nr, nc, gr, gc, h_scale, inv, cb, mask)
    if key < 0:
        return 0, 0
    return 1, _file(buckets, counts, key, nb)


@njit(cache=True, inline="always")
def _scan(flat, rows, cols, cur, r, c, d, gcur, w0, goal, rec, recg, parent, seen, gr, gc, h_scale, inv, cb, mask,
          buckets, counts, cap, flim):
    """Expand uniform cell ``cur`` reached by move ``d`` (0-7) by scanning: straight ahead after a straight
    arrival; after a diagonal one, along the diagonal and, from every cell it passes, along its two straight
    components. Each scan files only the cell it ends on (``_run``); the diagonal one stops at the first
    non-uniform cell, the goal, past f = ``flim`` or after ``cap`` steps. Returns (entries filed, the longest
    bucket after, cells passed). Inlined, and the count returned rather than kept in an array: an array
    passed to or made in the loop's function costs numba reference counting on every call."""
    dr, dc = _mdr(d), _mdc(d)
    added = most = 0
    if d < 4:
        n = _limit(r, c, dr, dc, rows, cols, cap)
        o = dr * cols + dc
        s = _run(flat, cur, o, cols if dr == 0 else 1, n, goal, gcur, w0, r, c, dr, dc, gr, gc, h_scale, flim)
        a, m = _jump_to(rec, recg, parent, d, cur + s * o, gcur + s * w0, cur, seen, r + s * dr, c + s * dc, goal,
                        gr, gc, h_scale, inv, cb, mask, buckets, counts)
        return a, m, s - 1
    kv = 1 if dr > 0 else 0
    kh = 3 if dc > 0 else 2
    ov = dr * cols
    z, zr, zc, gz = cur, r, c, gcur
    nd = _limit(r, c, dr, dc, rows, cols, cap)
    i = 0
    passed = 0
    while True:
        # z is uniform: its successors are the two straight components and the diagonal
        n = _limit(zr, zc, dr, 0, rows, cols, cap)
        s = _run(flat, z, ov, 1, n, goal, gz, w0, zr, zc, dr, 0, gr, gc, h_scale, flim)
        a, m = _jump_to(rec, recg, parent, kv, z + s * ov, gz + s * w0, cur, seen, zr + s * dr, zc, goal, gr, gc,
                        h_scale, inv, cb, mask, buckets, counts)
        added += a
        most = max(most, m)
        n = _limit(zr, zc, 0, dc, rows, cols, cap)
        t = _run(flat, z, dc, cols, n, goal, gz, w0, zr, zc, 0, dc, gr, gc, h_scale, flim)
        a, m = _jump_to(rec, recg, parent, kh, z + t * dc, gz + t * w0, cur, seen, zr, zc + t * dc, goal, gr, gc,
                        h_scale, inv, cb, mask, buckets, counts)
        added += a
        most = max(most, m)
        passed += s + t - 2
        i += 1
        z, zr, zc, gz = z + ov + dc, zr + dr, zc + dc, gz + SQRT2 * w0
        if (i >= nd or z == goal or not _uniform(flat, z, cols)
                or gz + h_scale * _octile(zr, zc, gr, gc) > flim):
            break
        passed += 1
    a, m = _jump_to(rec, recg, parent, d, z, gz, cur, seen, zr, zc, goal, gr, gc, h_scale, inv, cb, mask, buckets,
                    counts)
    return added + a, max(most, m), passed


@njit(cache=True)
def astar_jumps(costs, table, start, goal, rec, parent, stamp, esc_r2, esc_cost, h_scale, delta, nbuckets, cap,
                reach):
    """``_search.astar_buckets`` with scans through uniform cost-0 regions (see the module doc). Same record
    layout, plus ``parent`` (int32 per cell, written only for cells a scan files). ``nbuckets`` must cover
    ``jump_rise(cap, ...)``. Returns (found, expansions, cells scanned past). On failure the cells a scan
    passed are not closed: callers wanting the start's closed component rerun ``astar_buckets``."""
    rows, cols = costs.shape
    recg = rec.view(np.float32)
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    seen = stamp << STATE_SHIFT
    inv = 1.0 / delta
    mask = nbuckets - 1
    buckets = np.empty((nbuckets, 1024), np.int32)
    counts = np.zeros(nbuckets, np.int64)
    rec[2 * start] = seen - 1      # an earlier plan's state, so the start is filed below
    cb = int(h_scale * _octile(sr, sc, gr, gc) * inv)      # absolute index of the current bucket
    key = _relax(rec, recg, 8, start, 0.0, seen, sr, sc, gr, gc, h_scale, inv, cb, mask)
    fullest = _file(buckets, counts, key, start)
    # the loop's state between calls: current bucket, open entries, fullest bucket, expansions, cells scanned
    state = np.array([cb, 1, fullest, 0, 0], np.int64)
    drs = np.array([-1, 1, 0, 0, -1, -1, 1, 1])
    dcs = np.array([0, 0, -1, 1, -1, 1, -1, 1])
    burst = 2 * cap + 8        # the most entries one expansion can file
    while True:
        status = _expand_jumps(costs.ravel(), rows, cols, table, goal, rec, recg, parent, seen, esc_r2, esc_cost,
                               h_scale, delta, start, buckets, counts, state, drs, dcs, cap, reach, burst)
        if status != _NEED_ROOM:
            return status == _FOUND, state[3], state[4]
        buckets = _room(buckets, state[2] + burst)


@njit(cache=True)
def _expand_jumps(flat, rows, cols, table, goal, rec, recg, parent, seen, esc_r2, esc_cost, h_scale, delta,  # noqa: C901
                  start, buckets, counts, state, drs, dcs, cap, reach, burst):
    """``_search._expand`` plus the scan branch: a popped uniform cell (not the goal, reached by a move) is
    expanded by ``_scan``; any other cell as there, a filed one pruned by the move that ended its scan."""
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    inv = 1.0 / delta
    mask = buckets.shape[0] - 1
    room = buckets.shape[1] - burst
    w0 = table[0]
    cb, pending, fullest, expansions = state[0], state[1], state[2], state[3]
    scanned = state[4]
    far = int(np.sqrt(max(esc_r2, 0.0))) + 2
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
            d = _close(rec, recg, cur, seen, goal, gcur + h_scale * _octile(r, c, gr, gc))
            if d < 0:
                continue
            expansions += 1
            if d >= JUMP:
                d -= JUMP
            if d < 8 and cur != goal and 0 < r < rows - 1 and 0 < c < cols - 1 and _uniform(flat, cur, cols):
                added, most, passed = _scan(flat, rows, cols, cur, r, c, d, gcur, w0, goal, rec, recg, parent, seen,
                                            gr, gc, h_scale, inv, cb, mask, buckets, counts, cap,
                                            gcur + h_scale * _octile(r, c, gr, gc) + reach)
                scanned += passed
            elif _interior(r, c, rows, cols, sr, sc, far):
                if d == 0:
                    added, most = _expand_after(0, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 1:
                    added, most = _expand_after(1, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 2:
                    added, most = _expand_after(2, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 3:
                    added, most = _expand_after(3, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 4:
                    added, most = _expand_after(4, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 5:
                    added, most = _expand_after(5, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 6:
                    added, most = _expand_after(6, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                elif d == 7:
                    added, most = _expand_after(7, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                                h_scale, inv, cb, mask, buckets, counts)
                else:
                    added, most = _expand_after(8, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
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


@njit(cache=True)
def backtrack_jumps(costs, table, rec, parent, stamp, start, cell, esc_r2, esc_cost):
    """(cells, g) from ``start`` to ``cell`` after ``astar_jumps`` with ``stamp``: a cell a scan filed goes back
    to its ``parent`` along the scan's path (straight steps back, then diagonal ones: the reverse of the scan),
    with g added up from the parent's as the scan did; any other cell as in ``_search.backtrack``, to the closed
    neighbour whose g plus the move cost is smallest (straight ahead among equals)."""
    rows, cols = costs.shape
    flat = costs.ravel()
    recg = rec.view(np.float32)
    sr, sc = start // cols, start % cols
    this = stamp << STATE_SHIFT
    w0 = table[0]
    out = np.empty(256, np.int64)
    outg = np.empty(256, np.float64)
    m = 0
    cur = cell
    while m <= 2 * rows * cols:
        if m + 2 * (rows + cols) + 2 >= out.shape[0]:
            grown = np.empty(2 * out.shape[0] + 4 * (rows + cols), np.int64)
            grown[:m] = out[:m]
            out = grown
            grown_g = np.empty(grown.shape[0], np.float64)
            grown_g[:m] = outg[:m]
            outg = grown_g
        out[m] = cur
        outg[m] = np.float64(recg[2 * cur + 1])
        m += 1
        if cur == start:
            break
        st = rec[2 * cur]
        if (st >> 1) & 31 >= JUMP:
            x = parent[cur]
            xr, xc = x // cols, x - (x // cols) * cols
            r, c = cur // cols, cur - (cur // cols) * cols
            ar, ac = abs(r - xr), abs(c - xc)
            diag = min(ar, ac)
            straight = max(ar, ac) - diag
            sdr, sdc = np.sign(r - xr), np.sign(c - xc)
            tr = sdr if ar > ac else 0          # the straight part's step (after the diagonal part)
            tc = sdc if ac > ar else 0
            gx = np.float64(recg[2 * x + 1])
            # straight part back, then diagonal part back, excluding cur and x
            for j in range(straight - 1, -1, -1):
                if j == 0 and diag == 0:
                    break
                out[m] = (xr + diag * sdr + j * tr) * cols + xc + diag * sdc + j * tc
                outg[m] = gx + diag * SQRT2 * w0 + j * w0
                m += 1
            for i in range(diag - 1, 0, -1):
                out[m] = (xr + i * sdr) * cols + xc + i * sdc
                outg[m] = gx + i * SQRT2 * w0
                m += 1
            cur = x
            continue
        r = cur // cols
        c = cur - r * cols
        best = -1
        bestv = np.inf
        straight_p = -1
        straightv = np.inf
        ahead = cur + (cur - out[m - 2]) if m >= 2 else -1
        for k in range(8):
            pr, pc = _neighbour(r, c, k)
            if pr < 0 or pr >= rows or pc < 0 or pc >= cols:
                continue
            p = pr * cols + pc
            sp = rec[2 * p]
            if sp < this or not sp & 1:
                continue
            v = np.float64(recg[2 * p + 1]) + _move_cost(flat, table, cols, pr, pc, r, c, sr, sc, esc_r2, esc_cost)
            if v < bestv:
                bestv = v
                best = p
            if p == ahead:
                straight_p, straightv = p, v
        if best < 0:
            break
        cur = straight_p if straight_p >= 0 and straightv <= bestv * (1.0 + STRAIGHT_TOL) else best
    return out[:m][::-1].copy(), outg[:m][::-1].copy()
