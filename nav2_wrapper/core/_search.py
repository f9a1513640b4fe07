"""The 2D planner's numba kernels: one A* search, the path walk back, the Theta*-style shortcut, the densifier.

The search (``astar``) in one paragraph. Cells are flat indices ``row * cols + col`` of the costmap. Moving
into a cell costs its traversal factor ``table[cost]`` times the step length (1 or √2); blocked cells
(factor inf) may be entered at ``esc_cost`` only within ``sqrt(esc_r2)`` cells of the start (the escape
disc, so a robot whose start cell is inside the inflation band can leave), and a diagonal move may not
squeeze between two blocked orthogonal cells unless it enters the disc. The moves are one table (``DR``,
``DC``: up, down, left, right, then the diagonals); nothing is specialised per move. The queue is a ring of
float-keyed buckets (Dial's algorithm generalised): a cell with f = g + weight·h is appended to bucket
``floor(f / width)``; one move raises f by at most the dearest step plus √2·weight·h_scale, so the open cells
always fall in a window of ring buckets. Push and pop are O(1). Inside a bucket the order is last in, first
out: on a plateau of equal f (open space where the octile h is exact) the cell just reached, the deeper
one, is expanded next, so the search runs down the plateau instead of sweeping it breadth first.

Invariants (stated once, relied on by the planner and the tests):
- h = octile distance × ``h_scale`` (the cheapest factor) is consistent; with ``weight`` 1 the returned g
  of the goal is the optimal cost to a relative 1e-6 (float32 g, ``UB_TOL``); with weight w it is ≤ w × it.
- A cell expanded early inside its bucket (LIFO) is re-opened if a better g arrives later (label
  correcting); a bucket, once empty, holds only final g values, because anything cheaper would come through
  a cell of smaller f, and all of those are done.
- The search stops when a bucket is emptied and the goal's g is not above the next bucket's lower edge:
  every open cell has f ≥ that edge, so nothing cheaper can arrive. Cells popped with f ≥ the goal's g are
  closed unexpanded.
- An expansion skips the moves whose neighbour its predecessor p reaches strictly cheaper without it
  (``_dominated``): the three pointing back past p, and away from the map edge and the escape disc the side
  neighbours p reaches by its own diagonal or by two straight moves. p was expanded before, so those
  neighbours have that cheaper g already; no cheapest path needs the skipped moves.
- On failure (no path) every cell reachable from the start is closed.

Search state lives in one int32 buffer of 2 words per cell (an 8-byte record: a relaxation touches one
cache line): word 0 is ``stamp << STATE_SHIFT | move << 1 | closed`` (move 0-7: the move that last gave the
cell its g, 8: none), word 1 the g as float32 bits. The stamp lets the planner reuse the buffer between
plans without clearing it; the move is the parent pointer ``backtrack`` follows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SQRT2 = math.sqrt(2.0)
STATE_SHIFT = 5     # a record's state word: stamp << STATE_SHIFT | move << 1 | closed (see the module doc)
UB_TOL = 1e-6       # relative: a cell whose f is within this of the goal's g found so far is not expanded
# Relative: a g must improve by more than this to count. Equal-cost grid paths (straight and diagonal steps in
# another order) sum to float32 g values a few ulps apart; taking those "improvements" re-opened closed cells in
# cascades (1.5x the expansions on the bench maps). 4 float32 ulps.
G_TOL = 2.4e-7
# The 8-connected move table: row and column step of move k, up, down, left, right, then the diagonals.
DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], np.int64)
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], np.int64)
NO_MOVE = 8


def ring_size(width: float, max_step: float, weight: float, h_scale: float) -> int:
    """Buckets the ring needs (a power of two): one move raises f by at most ``max_step`` + √2·weight·h_scale."""
    rise = max_step + SQRT2 * weight * h_scale
    return 1 << max(3, int(math.ceil(math.log2(rise / width + 3))))


@njit(cache=True)
def astar(costs, table, start, goal, rec, stamp, esc_r2, esc_cost, weight, h_scale, width, nbuckets):
    """A* from cell ``start`` to ``goal`` (flat indices) on ``costs`` (uint8, rows×cols); see the module doc.

    ``table[c]`` is the traversal factor of cost c (inf = blocked), ``rec`` the search record, ``stamp`` this
    plan's stamp, ``width`` the bucket width and ``nbuckets`` the ring size (``ring_size``). Returns
    (found, expansions)."""
    rows, cols = costs.shape
    flat = costs.ravel()
    recg = rec.view(np.float32)
    sr, sc = start // cols, start % cols
    gr, gc = goal // cols, goal % cols
    seen = stamp << STATE_SHIFT
    hw = weight * h_scale
    far2 = (math.sqrt(max(esc_r2, 0.0)) + 2.0) ** 2    # beyond this from the start no neighbour is in the disc
    inv = 1.0 / width
    mask = nbuckets - 1
    offs = DR * cols + DC
    buckets = np.empty((nbuckets, 256), np.int32)
    counts = np.zeros(nbuckets, np.int64)
    # the start: g 0, no arrival move, filed in the bucket of its f
    rec[2 * start] = seen | (NO_MOVE << 1)
    recg[2 * start + 1] = 0.0
    cb = int(hw * _octile(sr, sc, gr, gc) * inv)       # absolute index of the current bucket
    buckets[cb & mask, 0] = start
    counts[cb & mask] = 1
    pending = 1
    expansions = 0
    while pending > 0:
        b = cb & mask
        while counts[b] > 0:
            counts[b] -= 1
            pending -= 1
            cur = buckets[b, counts[b]]
            st = rec[2 * cur]
            if st & 1:
                continue                                # a duplicate entry of a closed cell
            rec[2 * cur] = st | 1
            r = cur // cols
            c = cur - r * cols
            gcur = np.float64(recg[2 * cur + 1])
            if (rec[2 * goal] >= seen
                    and gcur + hw * _octile(r, c, gr, gc) >= np.float64(recg[2 * goal + 1]) * (1.0 - UB_TOL)):
                continue                                # cannot lead to a cheaper goal: closed unexpanded
            expansions += 1
            d = (st >> 1) & 15
            edge = r == 0 or c == 0 or r == rows - 1 or c == cols - 1
            plain = not edge and (r - sr) * (r - sr) + (c - sc) * (c - sc) > far2
            for k in range(8):
                if d != NO_MOVE and _dominated(flat, table, cur, d, k, cols, plain):
                    continue                            # the predecessor reaches that neighbour cheaper
                nr, nc = r + DR[k], c + DC[k]
                if edge and (nr < 0 or nr >= rows or nc < 0 or nc >= cols):
                    continue
                nb = cur + offs[k]
                w = _step(flat, table, cur, k, cols, (nr - sr) * (nr - sr) + (nc - sc) * (nc - sc) <= esc_r2,
                          esc_cost)
                if w == np.inf:
                    continue
                ng = np.float32(gcur + w)               # compared as stored: a rounding tie is no improvement
                nst = rec[2 * nb]
                old = np.float32(np.inf)
                if nst >= seen:
                    old = recg[2 * nb + 1]
                    if not ng < old * (1.0 - G_TOL):
                        continue                        # no better, or better by float rounding only
                rec[2 * nb] = seen | (k << 1)
                recg[2 * nb + 1] = ng
                key = max(int((ng + hw * _octile(nr, nc, gr, gc)) * inv), cb)
                if nst >= seen and not nst & 1 and max(int((old + hw * _octile(nr, nc, gr, gc)) * inv), cb) == key:
                    continue                            # its open entry is in that bucket already and reads the new g
                slot = key & mask
                if counts[slot] == buckets.shape[1]:
                    grown = np.empty((nbuckets, 2 * buckets.shape[1]), np.int32)
                    grown[:, :buckets.shape[1]] = buckets
                    buckets = grown
                buckets[slot, counts[slot]] = nb
                counts[slot] += 1
                pending += 1
        if rec[2 * goal] >= seen and np.float64(recg[2 * goal + 1]) <= (cb + 1) * width * (1.0 + UB_TOL):
            return True, expansions
        cb += 1
    return rec[2 * goal] >= seen and rec[2 * goal] & 1 == 1, expansions


@njit(cache=True)
def _dominated(flat, table, cur, d, k, cols, plain):
    """Whether move ``k`` out of ``cur`` (reached by move ``d`` from p = cur − d) can be skipped: p reaches that
    neighbour n strictly cheaper without ``cur``, and p has been expanded, so n has that g already. Always for
    the three moves pointing back past p (a shorter move from p, or p itself). For a ``plain`` cell (off the
    map edge and clear of the escape disc, so the weights are the table's): after a straight arrival, a side
    neighbour when p's diagonal costs less (√2·w(n) < w(cur) + w(n)); after a diagonal arrival, a side
    diagonal when p's two straight moves through m cost less (w(m) + w(n) < √2·(w(cur) + w(n)))."""
    dot = DR[k] * DR[d] + DC[k] * DC[d]
    if dot < 0:
        return True
    if not plain or (dot > 0 and (d >= 4 or k < 4)):
        return False
    wn = table[flat[cur + DR[k] * cols + DC[k]]]
    wc = table[flat[cur]]
    if dot > 0:     # a forward diagonal after a straight arrival: p's diagonal to the side cell s, then straight
        side = cur + (DR[k] - DR[d]) * cols + (DC[k] - DC[d])
        return SQRT2 * table[flat[side]] + wn <= wc + SQRT2 * wn
    if d < 4:
        return SQRT2 * wn < wc + wn
    m = cur - (DC[d] if DR[k] == DR[d] else DR[d] * cols)
    return table[flat[m]] + wn < SQRT2 * (wc + wn)


@njit(cache=True)
def _step(flat, table, cur, k, cols, in_disc, esc_cost):
    """Cost of move ``k`` out of cell ``cur``: the entered cell's factor (``esc_cost`` if it is blocked and
    ``in_disc``) times the step length; inf when blocked, or a diagonal squeezing between two blocked
    orthogonal cells outside the disc."""
    w = table[flat[cur + DR[k] * cols + DC[k]]]
    if w == np.inf:
        if not in_disc:
            return np.inf
        w = esc_cost
    if k < 4:
        return w
    if not in_disc and table[flat[cur + DR[k] * cols]] == np.inf and table[flat[cur + DC[k]]] == np.inf:
        return np.inf
    return SQRT2 * w


@njit(cache=True)
def _octile(r, c, tr, tc):
    dr = abs(r - tr)
    dc = abs(c - tc)
    return (dr + dc) + (SQRT2 - 2.0) * min(dr, dc)


def closed(rec: np.ndarray, cell: int, stamp: int) -> bool:
    """Whether the search with ``stamp`` closed ``cell`` (flat index)."""
    st = int(rec[2 * cell])
    return st >> STATE_SHIFT == stamp and bool(st & 1)


@njit(cache=True)
def backtrack(rec, cols, start, cell):
    """Flat cell indices from ``start`` to ``cell`` following each cell's arrival move back (the parent pointers
    of the last search), and g along them. With positive move costs the pointers form a tree rooted at the
    start (a cell's parent had a smaller g when it gave the cell its g, and g only decreases)."""
    recg = rec.view(np.float32)
    out = np.empty(256, np.int64)
    m = 0
    cur = cell
    while True:
        if m == out.shape[0]:
            grown = np.empty(2 * m, np.int64)
            grown[:m] = out
            out = grown
        out[m] = cur
        m += 1
        d = (rec[2 * cur] >> 1) & 15
        if cur == start or d == NO_MOVE:
            break
        cur -= DR[d] * cols + DC[d]
    cells = out[:m][::-1].copy()
    g = np.empty(m)
    for i in range(m):
        g[i] = recg[2 * cells[i] + 1]
    return cells, g


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
