"""numba kernels for the global planner: cost-aware 8-connected A*, the backtrack
that recovers a path from the search's g values, the line-of-sight shortcut pass and the path densifier.

Kept apart from planner.py so the Python-level logic stays readable; compiled with cache=True so only
the first process on a machine pays the compile time.

Search state lives in one int32 buffer of 2 words per cell (an 8-byte record: a relaxation reads and
writes one cache line, not three): word 0 is the state, word 1 the g (float32 bits). A state is
32·stamp + 2·move + closed for the plan with that stamp (``STATE_SHIFT``; move 0-7 is the move that last gave
the cell its g, 8 none, which the bucket kernel's pruning reads), so the buffer is reused between plans without
clearing. No parent array: ``backtrack`` walks the g values back. The open list is a 4-ary heap of single
int64 entries (f as float32 bits above the cell index): a heap move is one 8-byte copy, and a pop sifts
down half as many levels as in a binary heap.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

SQRT2 = math.sqrt(2.0)
STATE_SHIFT = 5     # a record state word: stamp << STATE_SHIFT | move << 1 | closed, move 0-8 (see the module doc)
STRAIGHT_TOL = 2e-7   # relative: a step within this of the cheapest counts as tying with it (float32 g)
TIE_EPS = 1e-6
UB_TOL = 1e-6   # relative: a cell whose f is within this of the goal's g found so far is not expanded
"""Relative weight added to h so that, among equal f = g + h, the node nearer the goal (larger g) pops first.

Open areas have long plateaus of equal f; without this the search fans out over the whole plateau. The
price is a (1 + TIE_EPS) bound on the path cost, the order of the float32 rounding of the stored g."""


@njit(cache=True, inline="always")
def _pack(f, idx):
    """One int64 heap entry: f as float32 bits (order-preserving for f >= 0) above the cell index."""
    return (np.int64(np.float32(f).view(np.int32)) << 32) | np.int64(idx)


@njit(cache=True, inline="always")
def _hpush(heap, n, e):
    i = n
    while i > 0:
        p = (i - 1) >> 2
        pe = heap[p]
        if pe <= e:
            break
        heap[i] = pe
        i = p
    heap[i] = e
    return n + 1


@njit(cache=True, inline="always")
def _hpop(heap, n):
    top = heap[0]
    n -= 1
    e = heap[n]
    i = 0
    while True:
        c = 4 * i + 1
        if c >= n:
            break
        m = c
        mv = heap[c]
        end = min(c + 4, n)
        for j in range(c + 1, end):
            if heap[j] < mv:
                m = j
                mv = heap[j]
        if e <= mv:
            break
        heap[i] = mv
        i = m
    heap[i] = e
    return top & 0xFFFFFFFF, n


@njit(cache=True, inline="always")
def _grow(heap, n):
    """The heap with room for at least one more entry."""
    if n < heap.shape[0]:
        return heap
    grown = np.empty(2 * heap.shape[0], np.int64)
    grown[:n] = heap[:n]
    return grown


@njit(cache=True, inline="always")
def _move_cost(flat, table, cols, fr, fc, tr, tc, sr, sc, esc_r2, esc_cost):
    """Cost of the 8-connected move (fr, fc) -> (tr, tc): the entered cell's traversal factor times the step
    length; cells within sqrt(esc_r2) of the start (sr, sc) are passable at ``esc_cost`` even when blocked;
    no diagonal squeeze between two blocked orthogonal cells (outside that escape disc). inf = not allowed."""
    f = table[flat[tr * cols + tc]]
    if f == np.inf:
        if (tr - sr) * (tr - sr) + (tc - sc) * (tc - sc) > esc_r2:
            return np.inf
        f = esc_cost
    if fr != tr and fc != tc:
        if (table[flat[fr * cols + tc]] == np.inf and table[flat[tr * cols + fc]] == np.inf
                and (tr - sr) * (tr - sr) + (tc - sc) * (tc - sc) > esc_r2):
            return np.inf
        return SQRT2 * f
    return f


@njit(cache=True, inline="always")
def _octile(r, c, tr, tc):
    dr = abs(r - tr)
    dc = abs(c - tc)
    return (dr + dc) + (SQRT2 - 2.0) * min(dr, dc)


@njit(cache=True, inline="always")
def _neighbour(r, c, k):
    """k-th of the 8 neighbours: the 4 orthogonal ones first."""
    if k < 4:
        return r + (k == 1) - (k == 0), c + (k == 3) - (k == 2)
    return r + (1 if k >= 6 else -1), c + (1 if (k & 1) else -1)


@njit(cache=True)
def astar(costs, table, start, goal, rec, stamp, esc_r2, esc_cost, h_weight, h_scale):
    """One-sided A* from cell ``start`` to ``goal`` (flat indices) on ``costs`` (uint8, rows×cols).

    ``table[c]`` is the traversal factor of cost c (inf = blocked); moves cost as in ``_move_cost``. The
    heuristic is the octile distance times ``h_scale`` (the smallest traversal factor, so it stays
    admissible and consistent) times ``h_weight`` (1.0 = cost-optimal). ``rec`` is the search record (see
    the module doc); on failure every cell reachable from the start is closed. Returns (found, expansions).
    """
    rows, cols = costs.shape
    flat = costs.ravel()
    recg = rec.view(np.float32)
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    heap = np.empty(1 << 14, np.int64)
    seen = stamp << STATE_SHIFT        # seen, move 0: this kernel does not prune by move
    done = seen + 1
    hw = h_weight * h_scale * (1.0 + TIE_EPS)
    recg[2 * start + 1] = 0.0
    rec[2 * start] = seen
    n = _hpush(heap, 0, _pack(0.0, start))
    expansions = 0
    while n > 0:
        cur, n = _hpop(heap, n)
        if rec[2 * cur] == done:
            continue
        rec[2 * cur] = done
        expansions += 1
        if cur == goal:
            return True, expansions
        r = cur // cols
        c = cur - r * cols
        gcur = np.float64(recg[2 * cur + 1])
        for k in range(8):
            nr, nc = _neighbour(r, c, k)
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            nb = nr * cols + nc
            st = rec[2 * nb]
            if st == done:
                continue
            step = _move_cost(flat, table, cols, r, c, nr, nc, sr, sc, esc_r2, esc_cost)
            if step == np.inf:
                continue
            ng = gcur + step
            if st != seen or ng < recg[2 * nb + 1]:
                rec[2 * nb] = seen
                recg[2 * nb + 1] = ng
                heap = _grow(heap, n)
                n = _hpush(heap, n, _pack(ng + hw * _octile(nr, nc, gr, gc), nb))
    return False, expansions


@intrinsic
def _prefetch(typingctx, arr, idx):
    """Hint the cache line holding ``arr[idx]`` toward L1 for writing (LLVM's prefetch: no fault on a bad address,
    no effect on any value)."""
    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        byte = ir.PointerType(ir.IntType(8))
        fnty = ir.FunctionType(ir.VoidType(), [byte, ir.IntType(32), ir.IntType(32), ir.IntType(32)])
        fn = builder.module.declare_intrinsic("llvm.prefetch", [byte], fnty)
        i32 = ir.IntType(32)
        builder.call(fn, [builder.bitcast(builder.gep(data, [args[1]]), byte), i32(1), i32(3), i32(1)])
        return context.get_dummy_value()
    return types.void(arr, idx), codegen


@njit(cache=True, inline="always")
def _u(i):
    """An index as unsigned: numba then skips the negative-index wraparound it adds to every signed index (a
    shift, an and, and the dimension kept in a register or reloaded from the stack, at each array access)."""
    return np.uint64(i)


@njit(cache=True, inline="always")
def _key(g, h, inv, cb, mask):
    """Ring slot of f = g + h (never below the current bucket: float rounding only)."""
    return max(int((g + h) * inv), cb) & mask


@njit(cache=True, inline="always")
def _relax(rec, recg, k, nb, ng, seen, nr, nc, gr, gc, h_scale, inv, cb, mask):
    """Give cell ``nb`` = (nr, nc) g = ``ng``, reached by move ``k``, if that is better. Returns the ring slot
    of the bucket it is to be appended to (``_file``), -1 if none (the heuristic is only computed when the g
    improves: most relaxations fail). Takes no bucket arrays: numba kept reference counting the ones passed
    into this branchy function on every call."""
    st = rec[_u(2 * nb)]
    if st >= seen:                  # seen or closed in this plan
        old = np.float64(recg[_u(2 * nb + 1)])
        if not ng < old:
            return -1
        rec[_u(2 * nb)] = seen | (k << 1)
        recg[_u(2 * nb + 1)] = ng
        h = h_scale * _octile(nr, nc, gr, gc)
        key = _key(ng, h, inv, cb, mask)
        if not st & 1 and _key(old, h, inv, cb, mask) == key:
            return -1               # its open entry is already in that bucket and reads the new g when popped
        return key
    rec[_u(2 * nb)] = seen | (k << 1)
    recg[_u(2 * nb + 1)] = ng
    return _key(ng, h_scale * _octile(nr, nc, gr, gc), inv, cb, mask)


@njit(cache=True, inline="always")
def _file(buckets, counts, key, nb):
    """Append cell ``nb`` to the bucket in ring slot ``key``; returns that bucket's new length. The caller
    guarantees room."""
    n = counts[_u(key)] + 1
    buckets[_u(key), _u(n - 1)] = nb
    counts[_u(key)] = n
    return n


@njit(cache=True, inline="always")
def _interior(r, c, rows, cols, sr, sc, far):
    """Off the map edge and more than ``far`` rows or columns from the start (outside any escape disc)."""
    return 0 < r < rows - 1 and 0 < c < cols - 1 and (abs(r - sr) > far or abs(c - sc) > far)


@njit(cache=True, inline="always")
def _close(rec, recg, cur, seen, goal, f):
    """Close the popped cell ``cur`` (f = ``f``); returns the move that gave it its g (8: none) when it is to be
    expanded, -1 if not: for a duplicate entry (closed already at this g) and for a cell that cannot lead to a
    cheaper goal than the one found (``_past_goal``): that one is closed unexpanded, so a better g found later
    re-files it like any closed cell."""
    st = rec[_u(2 * cur)]
    if st < seen or st & 1:
        return -1
    rec[_u(2 * cur)] = st | 1
    if _past_goal(rec, recg, seen, goal, f):
        return -1
    return (st >> 1) & 15


@njit(cache=True, inline="always")
def _past_goal(rec, recg, seen, goal, f):
    """True when the goal already has a g in this plan and ``f`` is not below it (within UB_TOL)."""
    return rec[_u(2 * goal)] >= seen and f >= np.float64(recg[_u(2 * goal + 1)]) * (1.0 - UB_TOL)


@njit(cache=True, inline="always")
def _room(buckets, need):
    """The bucket ring with room for ``need`` entries per bucket (doubled when short)."""
    if need <= buckets.shape[1]:
        return buckets
    grown = np.empty((buckets.shape[0], 2 * buckets.shape[1]), np.int32)
    grown[:, :buckets.shape[1]] = buckets
    return grown


# _expand's outcomes
_FOUND = 1
_EXHAUSTED = 0
_NEED_ROOM = -1


@njit(cache=True, inline="always")
def open_buckets(costs, start, goal, rec, stamp, h_scale, delta, nbuckets, nstate):
    """A bucket search's starting state, shared by the bucket and chained kernels: the float32 view of the
    records, this plan's stamp bits, the bucket ring with the start filed, and the loop state carried between
    calls of the expansion loop (``nstate`` words: current bucket, open entries, fullest bucket, expansions, then
    zeros for the kernel's own counters), plus the neighbour offsets (up, down, left, right, then the diagonals
    up-left, up-right, down-left, down-right)."""
    cols = costs.shape[1]
    recg = rec.view(np.float32)
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    seen = stamp << STATE_SHIFT
    inv = 1.0 / delta
    buckets = np.empty((nbuckets, 1024), np.int32)
    counts = np.zeros(nbuckets, np.int64)
    rec[2 * start] = seen - 1      # an earlier plan's state, so the start is filed below
    cb = int(h_scale * _octile(sr, sc, gr, gc) * inv)      # absolute index of the current bucket
    key = _relax(rec, recg, 8, start, 0.0, seen, sr, sc, gr, gc, h_scale, inv, cb, nbuckets - 1)
    fullest = _file(buckets, counts, key, start)
    state = np.zeros(nstate, np.int64)
    state[0], state[1], state[2] = cb, 1, fullest
    drs = np.array([-1, 1, 0, 0, -1, -1, 1, 1])
    dcs = np.array([0, 0, -1, 1, -1, 1, -1, 1])
    return recg, seen, buckets, counts, state, drs, dcs


@njit(cache=True)
def astar_buckets(costs, table, start, goal, rec, stamp, esc_r2, esc_cost, h_scale, delta, nbuckets):
    """Cost-optimal A* (h = octile distance × ``h_scale``, consistent) with a bucket queue instead of a heap.

    With a consistent heuristic the keys f = g + h of expanded cells never decrease, and one move raises f
    by at most (max step + √2·h_scale), so the open cells always fall into a sliding window of
    ``nbuckets`` buckets of width ``delta`` (a ring of arrays). Push and pop are O(1), no sifting.
    Inside a bucket the order is last in, first out, so a cell may be expanded before its best g is
    known (the bucket spans f values up to ``delta`` apart); it is then re-opened when the better g arrives
    (label correcting inside the bucket). Once a bucket is empty every cell with f in it has its final g,
    because anything cheaper would come through a cell with a smaller f, all of which are done.
    LIFO in narrow buckets is the tie-break: where f is flat (free space between the last obstacle and
    the goal, where the octile h is exact, often thousands of cells with f = C*), the cell just reached
    from the one being expanded, the deeper one, comes next, so the search runs down the plateau to the
    goal instead of sweeping it breadth first. Once the goal has a g, a popped cell whose f is not below it
    (within ``UB_TOL``) is closed without being expanded: no path through it is cheaper (h is a lower
    bound). The search ends when a bucket is emptied and the goal's g is not above the next bucket's lower
    edge (within UB_TOL): every open cell then has f >= that edge, so nothing cheaper can arrive and the
    g is exact (to that relative tolerance, the order of the float32 rounding of the stored g).
    Cells away from the map edge and from the start's escape disc (nearly all) take a branch-light path:
    fixed flat offsets, no bounds checks, the four orthogonal factors loaded once and reused for the
    diagonal-squeeze test, and no relaxation of the three neighbours behind the move that gave the cell its
    g (kept in the cell's state word): the predecessor p and the two cells next to both, which p reaches
    directly by a move costing less than any detour through this cell; nor of the two side neighbours when
    p reaches them strictly cheaper without this cell (``_expand_after``). A skipped move is never on a cheapest
    path, so every g stays exact. Same record layout and return value as ``astar``; on failure every cell
    reachable from the start is closed.
    """
    rows, cols = costs.shape
    recg, seen, buckets, counts, state, drs, dcs = open_buckets(costs, start, goal, rec, stamp, h_scale, delta,
                                                                 nbuckets, 4)
    while True:
        status = _expand(costs.ravel(), rows, cols, table, goal, rec, recg, seen, esc_r2, esc_cost, h_scale,
                         delta, start, buckets, counts, state, drs, dcs)
        if status != _NEED_ROOM:
            return status == _FOUND, state[3]
        buckets = _room(buckets, state[2] + 8)


@njit(cache=True)
def _expand(flat, rows, cols, table, goal, rec, recg, seen, esc_r2, esc_cost, h_scale, delta, start, buckets,
            counts, state, drs, dcs):
    """The expansion loop of ``astar_buckets`` from ``state``; returns _FOUND, _EXHAUSTED or, before a pop that
    could overflow a bucket, _NEED_ROOM (state saved: the caller grows ``buckets`` and calls again). A separate
    function that creates no array and reassigns none: an array made or regrown in the loop's function is
    reference-counted by numba on every relaxation that passes it to a helper (an atomic add and a call each,
    12 % of the search time)."""
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    inv = 1.0 / delta
    mask = buckets.shape[0] - 1
    room = buckets.shape[1] - 8
    cb, pending, fullest, expansions = state[0], state[1], state[2], state[3]
    far = int(math.sqrt(max(esc_r2, 0.0))) + 2        # rows/cols from the start beyond which no escape applies
    while pending > 0:
        b = cb & mask
        while counts[b] > 0:
            if fullest > room:
                state[0], state[1], state[2], state[3] = cb, pending, fullest, expansions
                return _NEED_ROOM
            counts[b] -= 1              # last in, first out: see the docstring
            cur = buckets[_u(b), _u(counts[b])]
            pending -= 1
            r = cur // cols
            c = cur - r * cols
            gcur = np.float64(recg[_u(2 * cur + 1)])
            d = _close(rec, recg, cur, seen, goal, gcur + h_scale * _octile(r, c, gr, gc))
            if d < 0:
                continue
            expansions += 1
            if _interior(r, c, rows, cols, sr, sc, far):
                added, most = _expand_interior(d, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc,
                                               h_scale, inv, cb, mask, buckets, counts)
                pending += added
                fullest = max(fullest, most)
            else:
                added, most = _expand_border(flat, rows, cols, table, r, c, gcur, rec, recg, seen, sr, sc, gr, gc,
                                             esc_r2, esc_cost, h_scale, inv, cb, mask, buckets, counts, drs, dcs)
                pending += added
                fullest = max(fullest, most)
        if _past_goal(rec, recg, seen, goal, (cb + 1) * delta):     # every open f >= the next bucket's edge
            state[3] = expansions
            return _FOUND
        cb += 1
    state[3] = expansions
    return _EXHAUSTED


@njit(cache=True, inline="always")
def _mdr(k):
    """Row step of move k (see _neighbour)."""
    return (k == 1) - (k == 0) if k < 4 else (1 if k >= 6 else -1)


@njit(cache=True, inline="always")
def _mdc(k):
    """Column step of move k."""
    return (k == 3) - (k == 2) if k < 4 else (1 if k & 1 else -1)


@njit(cache=True, inline="always")
def _orth(dr, dc):
    """Index of the orthogonal move (dr, dc)."""
    return (1 if dr == 1 else 0) if dr != 0 else (3 if dc == 1 else 2)


@njit(cache=True, inline="always")
def _pick(i, f0, f1, f2, f3):
    return f0 if i == 0 else (f1 if i == 1 else (f2 if i == 2 else f3))


@njit(cache=True, inline="always")
def _expand_after(d, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask, buckets,
                  counts):
    """Relax the neighbours of interior cell ``cur`` worth relaxing given the move ``d`` that gave it its g (8:
    none, all are). Skipped: the three behind d (negative dot product: from the predecessor p = cur − d each
    is p itself or one move from p that costs less than going through cur); the side neighbours p reaches
    strictly cheaper without cur: after a straight arrival by p's diagonal move (√2·w(n) < w(cur) + w(n)),
    after a diagonal one by two straight moves through m (w(m) + w(n) < √2·(w(cur) + w(n))); and after a
    straight arrival the forward diagonals p reaches at no more cost diagonal-first through the side cell s
    (√2·w(s) + w(n) ≤ w(cur) + √2·w(n)): the canonical order of grid paths, ties go to the diagonal-first
    one, which is never skipped itself (from s, n is straight ahead). A skipped move is never needed for a
    cheapest path. Called with ``d`` a literal (one copy per arrival move) and k unrolled, every test on d
    and k folds to a constant: the branches left are on the weights, where a table-driven version loaded
    masks and moved through a bit loop (5 % slower). Returns (entries filed, the longest bucket after)."""
    f0 = table[flat[_u(cur - cols)]]
    f1 = table[flat[_u(cur + cols)]]
    f2 = table[flat[_u(cur - 1)]]
    f3 = table[flat[_u(cur + 1)]]
    wc = table[flat[_u(cur)]]
    ddr, ddc = _mdr(d), _mdc(d)
    added = most = 0
    for k in range(8):
        kdr, kdc = _mdr(k), _mdc(k)
        nb = cur + kdr * cols + kdc
        dot = kdr * ddr + kdc * ddc
        if d < 8 and dot < 0:
            continue                            # behind the arrival: the predecessor reaches it cheaper
        if k < 4:
            f = _pick(k, f0, f1, f2, f3)
            if d < 4 and dot == 0 and SQRT2 * f < wc + f:
                continue                        # side: the predecessor's diagonal is cheaper
        else:
            if _pick(_orth(kdr, 0), f0, f1, f2, f3) == np.inf and _pick(_orth(0, kdc), f0, f1, f2, f3) == np.inf:
                continue                        # no squeeze between two blocked orthogonal cells
            wn = table[flat[_u(nb)]]
            if d < 4 and dot > 0:               # forward diagonal after a straight move: diagonal-first wins ties
                if SQRT2 * _pick(_orth(kdr - ddr, kdc - ddc), f0, f1, f2, f3) + wn <= wc + SQRT2 * wn:
                    continue
            elif 4 <= d < 8 and dot == 0:       # side diagonal after a diagonal move: two straight moves cheaper
                m = _orth(0 if kdr == ddr else kdr, 0 if kdc == ddc else kdc)
                if _pick(m, f0, f1, f2, f3) + wn < SQRT2 * (wc + wn):
                    continue
            f = SQRT2 * wn
        if f == np.inf:
            continue
        key = _relax(rec, recg, k, nb, gcur + f, seen, r + kdr, c + kdc, gr, gc, h_scale, inv, cb, mask)
        if key >= 0:
            most = max(most, _file(buckets, counts, key, nb))
            added += 1
            # the record straight ahead of nb: nb is often popped next (LIFO) and reads it then
            _prefetch(rec, 2 * (2 * nb - cur))
    return added, most


@njit(cache=True, inline="always")
def _expand_interior(d, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask, buckets,
                     counts):
    """``_expand_after`` for arrival move ``d`` (0-8), with one inlined copy per move so that its pruning rules
    fold to constants (a variable ``d`` would keep every move test in the hot loop)."""
    if d == 0:
        return _expand_after(0, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 1:
        return _expand_after(1, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 2:
        return _expand_after(2, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 3:
        return _expand_after(3, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 4:
        return _expand_after(4, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 5:
        return _expand_after(5, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 6:
        return _expand_after(6, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    if d == 7:
        return _expand_after(7, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                             buckets, counts)
    return _expand_after(8, cur, r, c, gcur, cols, flat, table, rec, recg, seen, gr, gc, h_scale, inv, cb, mask,
                         buckets, counts)

@njit(cache=True)
def _expand_border(flat, rows, cols, table, r, c, gcur, rec, recg, seen, sr, sc, gr, gc, esc_r2, esc_cost,
                   h_scale, inv, cb, mask, buckets, counts, drs, dcs):
    """Expand a cell on the map edge or near the start (the escape disc): bounds-checked, ``_move_cost``'s full
    rules, no pruning. Returns (entries filed, the longest bucket after filing)."""
    added = most = 0
    for k in range(8):
        nr, nc = r + drs[k], c + dcs[k]
        if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
            continue
        f = _move_cost(flat, table, cols, r, c, nr, nc, sr, sc, esc_r2, esc_cost)
        if f == np.inf:
            continue
        key = _relax(rec, recg, k, nr * cols + nc, gcur + f, seen, nr, nc, gr, gc, h_scale, inv, cb, mask)
        if key >= 0:
            most = max(most, _file(buckets, counts, key, nr * cols + nc))
            added += 1
    return added, most


def closed(rec: np.ndarray, cell: int, stamp: int) -> bool:
    """Whether the search with ``stamp`` closed ``cell`` (flat index)."""
    st = int(rec[2 * cell])
    return st >> STATE_SHIFT == stamp and bool(st & 1)


@njit(cache=True)
def backtrack(costs, table, rec, stamp, start, cell, esc_r2, esc_cost):
    """Flat cell indices from ``start`` to ``cell`` through the cells the last ``astar`` with ``stamp`` closed.

    Each step goes back to the closed neighbour whose g plus the move cost is smallest: that is the
    neighbour the search relaxed the cell from (or one tying with it), so the path's cost is the search's
    g; among ties the one straight ahead wins. g drops by at least 1 per step, so the walk ends at the
    start (g = 0).
    """
    rows, cols = costs.shape
    flat = costs.ravel()
    recg = rec.view(np.float32)
    sr, sc = start // cols, start % cols
    this = stamp << STATE_SHIFT
    out = np.empty(256, np.int64)
    m = 0
    cur = cell
    while m <= rows * cols:
        if m >= out.shape[0]:
            grown = np.empty(2 * out.shape[0], np.int64)
            grown[:m] = out[:m]
            out = grown
        out[m] = cur
        m += 1
        if cur == start:
            break
        r = cur // cols
        c = cur - r * cols
        best = -1
        bestv = np.inf
        straight = -1               # the neighbour that keeps the last step's direction
        straightv = np.inf
        ahead = cur + (cur - out[m - 2]) if m >= 2 else -1
        # Off the map edge and outside the escape disc every move into cur costs w(cur) times its length (or is a
        # squeeze): what _move_cost gives, with w(cur) and the four orthogonal weights loaded once, not per move.
        plain = 0 < r < rows - 1 and 0 < c < cols - 1 and (r - sr) * (r - sr) + (c - sc) * (c - sc) > esc_r2
        if plain:
            wcur = table[flat[cur]]
            blocked_up = table[flat[cur - cols]] == np.inf
            blocked_down = table[flat[cur + cols]] == np.inf
            blocked_left = table[flat[cur - 1]] == np.inf
            blocked_right = table[flat[cur + 1]] == np.inf
        for k in range(8):
            pr, pc = _neighbour(r, c, k)
            if pr < 0 or pr >= rows or pc < 0 or pc >= cols:
                continue
            p = pr * cols + pc
            st = rec[2 * p]
            if st < this or not st & 1:    # not closed in this plan
                continue
            if not plain:
                step = _move_cost(flat, table, cols, pr, pc, r, c, sr, sc, esc_r2, esc_cost)
            elif k < 4:
                step = wcur
            elif (blocked_up if pr < r else blocked_down) and (blocked_left if pc < c else blocked_right):
                step = np.inf
            else:
                step = SQRT2 * wcur
            v = np.float64(recg[2 * p + 1]) + step
            if v < bestv:
                bestv = v
                best = p
            if p == ahead:
                straight, straightv = p, v
        if best < 0:
            break
        # Equal-cost alternatives differ only by float32 rounding of g: among them keep going straight, so the
        # path has as few turns as its cost allows whatever order the search closed cells in.
        cur = straight if straight >= 0 and straightv <= bestv * (1.0 + STRAIGHT_TOL) else best
    return out[:m][::-1].copy()


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
    is collision-free and no costlier than the sub-path it replaces. Returns indices of kept vertices.

    While the path from vertex i runs straight on in one of the 8 directions, the segment to the next vertex visits
    exactly the cells the last one did plus that vertex (and, on a diagonal, checks its two corner cells), so its
    cost is extended by one cell in the same order ``segment_cost`` sums, the same float result, instead of walked
    again from i: the walk is quadratic in the run's length."""
    cols = costs.shape[1]
    flat = costs.ravel()
    n = path.shape[0]
    keep = np.empty(n, np.int64)
    m = 0
    i = 0
    keep[m] = 0
    m += 1
    while i < n - 1:
        best = i + 1
        r0, c0 = path[i] // cols, path[i] % cols
        dr, dc = path[i + 1] // cols - r0, path[i + 1] % cols - c0
        run = True                      # vertices i..j-1 lie on one straight line of unit steps (dr, dc)
        total = table[flat[path[i + 1]]]
        if dr != 0 and dc != 0 and (table[flat[r0 * cols + c0 + dc]] == np.inf
                                    or table[flat[(r0 + dr) * cols + c0]] == np.inf):
            total = np.inf              # the first diagonal step's corner: every segment from i crosses it
        for j in range(i + 2, n):
            r1, c1 = path[j] // cols, path[j] % cols
            rp, cp = path[j - 1] // cols, path[j - 1] % cols
            if run and r1 - rp == dr and c1 - cp == dc:
                if total != np.inf and dr != 0 and dc != 0 and (table[flat[rp * cols + cp + dc]] == np.inf
                                                                 or table[flat[(rp + dr) * cols + cp]] == np.inf):
                    total = np.inf
                total += table[flat[path[j]]]
                if total == np.inf:
                    sc = np.inf
                else:
                    dx = float(c1 - c0)
                    dy = float(r1 - r0)
                    sc = math.sqrt(dx * dx + dy * dy) * total / (j - i)
            else:
                run = False
                sc = segment_cost(costs, table, r0, c0, r1, c1)
            if sc == np.inf or sc > (gvals[j] - gvals[i]) * (1.0 + slack) + 1e-9:
                break
            best = j
        keep[m] = best
        m += 1
        i = best
    return keep[:m]


@njit(cache=True)
def densify(pts, spacing):
    """``pts`` (N ≥ 2, 2) with each segment split into ceil(length / spacing) equal steps (at least one). One pass,
    no temporaries: the numpy version of the same arithmetic cost ~0.1 ms a plan in array set-up alone."""
    m = pts.shape[0]
    steps = np.empty(m - 1, np.int64)
    total = 1
    for i in range(m - 1):
        n = int(math.ceil(math.hypot(pts[i + 1, 0] - pts[i, 0], pts[i + 1, 1] - pts[i, 1]) / spacing))
        steps[i] = max(1, n)
        total += steps[i]
    out = np.empty((total, 2))
    out[0] = pts[0]
    j = 1
    for i in range(m - 1):
        n = steps[i]
        dx = pts[i + 1, 0] - pts[i, 0]
        dy = pts[i + 1, 1] - pts[i, 1]
        for k in range(1, n + 1):
            t = k / n
            out[j, 0] = pts[i, 0] + t * dx
            out[j, 1] = pts[i, 1] + t * dy
            j += 1
    return out
