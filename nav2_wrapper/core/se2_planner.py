"""Footprint-aware global planning: a lattice search over (x, y, heading) for the rectangular holonomic base.

The 2D planner searches for a disc of the inscribed radius, so in clutter it can route through a gap that the
disc fits but the 0.70 × 0.50 m rectangle does not fit at any heading; following such a path wedges the robot.
This search is the fallback the navigator runs when the heading assignment along the 2D path finds a point where
no heading fits. It is sound by construction: a state (cell centre, heading bin) is free only if the footprint's
bounding rectangle, grown by ``margin``, overlaps no lethal cell (an exact rectangle-square overlap test per
cell), and every move lands on a free state — translations keep the heading, turns change it by one bin and
need both bins free at that position.

Work is bounded twice: only a window around the start, the goal and the 2D path is searched (so a 2000 × 2000
map costs what the neighbourhood of the route costs), and the search stops after ``max_expansions`` states.
The heuristic is the exact 2D cost to go over cells free at *some* heading, which makes dead-end pockets cheap
to rule out and keeps the expansions close to the states on the final route.

Unknown cells count as free (like the 2D planner with ``allow_unknown``), at the planner's unknown cost.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_common.params import param

from . import _se2_search
from .costmap import Costmap
from .costs import LETHAL, MAX_NON_OBSTACLE, NO_INFORMATION
from .footprint import Footprint


@dataclass
class Se2PlannerConfig:
    """The SE(2) fallback's parameters (``planner_server.<plugin>`` keys prefixed ``se2_``)."""

    enabled: bool = param(True, "run the (x, y, heading) search when no heading fits somewhere on the 2D path")
    bins: int = param(36, "heading bins over a half turn (the rectangle is symmetric under a half turn)",
                      ge=4, le=180)
    margin: float = param(0.01, "clearance the footprint keeps from lethal cells on the SE(2) path, on top of "
                                "the allowance for moves between lattice states (res/√2)", unit="m", ge=0, le=0.5)
    rotation_cost: float = param(
        0.5, "cost of turning one radian, in metres of travel (discourages needless turning)", unit="m/rad", ge=0)
    window_margin: float = param(2.0, "the search window is the box around start, goal and 2D path grown by this "
                                      "(doubled while the goal is cut off inside it, up to max_window_cells)",
                                 unit="m", ge=0)
    max_window_cells: int = param(250_000, "the window is not grown beyond this many cells (memory: ~10 bytes "
                                           "per cell and heading bin)", ge=1000)
    max_expansions: int = param(3_000_000, "the search gives up after expanding this many states", ge=1000)
    tick_expansions: int = param(
        80_000, "while the robot follows a path, a search runs in slices of this many states per control tick "
                "(the live loop plans inside its tick: this bounds the stall), following the current path meanwhile",
        ge=1000)
    heuristic_weight: float = param(1.0, "weighted A* on the SE(2) lattice (1: cost-optimal)", ge=1.0)
    reuse_deviation: float = param(0.5, "the previous SE(2) path is kept at a replan only while the robot is "
                                        "within this distance of it (and every pose of its rest still fits)",
                                   unit="m", ge=0)
    escape_radius: float = param(0.15, "how far from the start blocked states may be crossed (a body touching "
                                       "a noise speckle must be able to leave)", unit="m", ge=0)


@dataclass
class Se2Plan:
    """A path with a heading per point (rad, modulo a half turn), or ok=False with the reason."""

    ok: bool
    path: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    headings: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    reason: str = ""
    length: float = 0.0
    expansions: int = 0
    seconds: float = 0.0


def box_half_extents(footprint: Footprint) -> tuple[float, float]:
    """The centred rectangle bounding the footprint polygon (exact for the rectangular base)."""
    poly = footprint.polygon
    return float(np.max(np.abs(poly[:, 0]))), float(np.max(np.abs(poly[:, 1])))


def kernel_rows(half_len: float, half_wid: float, yaw: float, res: float) -> tuple[int, NDArray, NDArray]:
    """(pad, lo, hi): for each row offset di in −pad … pad, the column offsets dj whose cell square (side
    ``res``, centred at (dj, di)·res from the body centre) overlaps the rectangle turned by ``yaw``.

    Separating-axis test between the axis-aligned square and the turned rectangle; the overlap region is
    convex, so each row is one interval."""
    cs, sn = abs(math.cos(yaw)), abs(math.sin(yaw))
    h = res / 2
    ext_x, ext_y = half_len * cs + half_wid * sn, half_len * sn + half_wid * cs
    pad = int(math.ceil((max(ext_x, ext_y) + h) / res))
    d = np.arange(-pad, pad + 1) * res
    dx, dy = np.meshgrid(d, d)           # dx varies along columns, dy along rows
    c, s = math.cos(yaw), math.sin(yaw)
    overlap = ((np.abs(dx) <= ext_x + h) & (np.abs(dy) <= ext_y + h)
               & (np.abs(dx * c + dy * s) <= half_len + h * (cs + sn))
               & (np.abs(-dx * s + dy * c) <= half_wid + h * (cs + sn)))
    lo = np.full(2 * pad + 1, 1, np.int64)
    hi = np.zeros(2 * pad + 1, np.int64)
    for k in range(2 * pad + 1):
        cols = np.flatnonzero(overlap[k])
        if len(cols):
            lo[k], hi[k] = cols[0] - pad, cols[-1] - pad
    return pad, lo, hi


@dataclass
class _Window:
    """The searched part of the costmap: rows r0..r1-1, cols c0..c1-1."""

    r0: int
    r1: int
    c0: int
    c1: int

    @property
    def shape(self) -> tuple[int, int]:
        return self.r1 - self.r0, self.c1 - self.c0


class Se2Planner:
    """Plans (x, y, heading) paths for a rectangular footprint on a Costmap's master costs."""

    def __init__(self, cfg: Se2PlannerConfig, footprint: Footprint) -> None:
        self.cfg = cfg
        self.half_len, self.half_wid = box_half_extents(footprint)
        self._kernels: dict[float, list[tuple[int, NDArray, NDArray]]] = {}
        self._res = 0.0

    def grow(self, res: float) -> float:
        """How much the rectangle is grown for the collision grids: ``margin`` plus what makes the check hold
        between lattice states too — every pose on a move between two cell centres lies within res/√2 of one
        end (a diagonal's midpoint), and a turn by one bin moves a corner at most r·dθ/2 from either end."""
        sweep = max(res / math.sqrt(2.0), math.hypot(self.half_len, self.half_wid) * math.pi / self.cfg.bins / 2)
        return self.cfg.margin + sweep

    def _kernel_set(self, res: float) -> list[tuple[int, NDArray, NDArray]]:
        if res not in self._kernels:
            m = self.grow(res)
            self._kernels[res] = [kernel_rows(self.half_len + m, self.half_wid + m, b * math.pi / self.cfg.bins, res)
                                  for b in range(self.cfg.bins)]
        return self._kernels[res]

    def blocked_grids(self, costmap: Costmap, win: _Window) -> NDArray[np.bool_]:
        """(bins, rows, cols) of the window: whether the grown footprint at that cell centre and bin heading
        overlaps a lethal cell (cells off the costmap are not lethal, as in the controllers' checks)."""
        kernels = self._kernel_set(costmap.resolution)
        pad = max(k[0] for k in kernels)
        rows, cols = costmap.shape
        lethal = np.zeros((win.r1 - win.r0 + 2 * pad, win.c1 - win.c0 + 2 * pad), np.uint8)
        sr0, sr1 = max(0, win.r0 - pad), min(rows, win.r1 + pad)
        sc0, sc1 = max(0, win.c0 - pad), min(cols, win.c1 + pad)
        lethal[sr0 - (win.r0 - pad):sr1 - (win.r0 - pad), sc0 - (win.c0 - pad):sc1 - (win.c0 - pad)] = (
            costmap.costs[sr0:sr1, sc0:sc1] == LETHAL)
        lo_all = np.ones((len(kernels), 2 * pad + 1), np.int64)     # rows a kernel lacks stay empty (lo > hi)
        hi_all = np.zeros((len(kernels), 2 * pad + 1), np.int64)
        for b, (p, lo, hi) in enumerate(kernels):
            lo_all[b, pad - p:pad + p + 1], hi_all[b, pad - p:pad + p + 1] = lo, hi
        out = np.empty((len(kernels), *win.shape), np.bool_)
        _se2_search.dilate_rows(lethal, pad, lo_all, hi_all, self._decided(lethal, pad, costmap.resolution), out)
        return out

    def _decided(self, lethal: NDArray[np.uint8], pad: int, res: float) -> NDArray[np.uint8]:
        """Per window cell: 0 free at every heading (the nearest lethal cell is beyond the grown rectangle's
        circumscribed circle plus a cell's half diagonal), 1 blocked at every heading (a lethal cell centre lies
        in its inscribed circle), 2 undecided. Most cells of a sparse map are 0, and the per-heading test then
        runs only in the band around obstacles."""
        from scipy.ndimage import distance_transform_edt

        grow = self.grow(res)
        dist = distance_transform_edt(lethal == 0)[pad:lethal.shape[0] - pad, pad:lethal.shape[1] - pad] * res
        out = np.full(dist.shape, 2, np.uint8)
        out[dist > math.hypot(self.half_len + grow, self.half_wid + grow) + res / math.sqrt(2.0) + 1e-9] = 0
        out[dist <= self.half_wid + grow] = 1
        return out

    def feasible_bins(self, costmap: Costmap, points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """(N, bins): whether the grown footprint fits at each point (its cell) and bin heading — the same
        collision model the search uses, so a 2D path that passes here needs no fallback. Points off the window
        (there is none: it is built around them) or off the costmap count as fitting nowhere."""
        win = self._window(costmap, points, 0.0)
        blocked = self.blocked_grids(costmap, win)
        col, row = costmap.world_to_cell(points[:, 0], points[:, 1])
        inside = (row >= win.r0) & (row < win.r1) & (col >= win.c0) & (col < win.c1)
        out = np.zeros((len(points), self.cfg.bins), np.bool_)
        out[inside] = ~blocked[:, row[inside] - win.r0, col[inside] - win.c0].T
        return out

    def _heuristic(self, blocked: NDArray[np.bool_], factor: NDArray[np.float32], start: tuple[int, int],
                   goal: tuple[int, int], k: int) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """(2D cost to go over cells free at some heading, the goal cells); the cells near the start count as
        free (the escape zone), so a start touching a speckle still has a finite estimate."""
        esc = self.cfg.escape_radius / (self._res or 1.0)
        rr, cc = np.mgrid[0:blocked.shape[1], 0:blocked.shape[2]]
        near_start = (rr - start[0]) ** 2 + (cc - start[1]) ** 2 <= esc * esc
        passable = ~blocked.all(axis=0) | near_start
        goals = self._goal_cells(passable, goal[0], goal[1], k)
        h = np.full(passable.shape, np.inf)
        if len(goals):
            _se2_search.cost_to_go(passable, factor, goals, h)
        return h, goals

    def _window(self, costmap: Costmap, pts: NDArray[np.float64], margin: float) -> _Window:
        col, row = costmap.world_to_cell(pts[:, 0], pts[:, 1])
        m = int(math.ceil(margin / costmap.resolution))
        rows, cols = costmap.shape
        return _Window(max(0, int(row.min()) - m), min(rows, int(row.max()) + m + 1),
                       max(0, int(col.min()) - m), min(cols, int(col.max()) + m + 1))

    def plan(self, costmap: Costmap, start: tuple[float, float, float], goal: tuple[float, float],
             table: NDArray[np.float64], tolerance: float = 0.0,
             guide: NDArray[np.float64] | None = None) -> Se2Plan:
        """A path from the start pose to the goal point; ``table`` is the 2D planner's traversal factor per cost
        value (its blocked entries are only charged here: where the body may go is the collision grids' say),
        ``guide`` the 2D path whose neighbourhood is searched too. Runs to the end (``max_expansions``)."""
        search = self.begin(costmap, start, goal, table, tolerance, guide)
        if isinstance(search, Se2Plan):
            return search
        out = search.advance(self.cfg.max_expansions)
        assert out is not None      # the whole budget was given
        return out

    def begin(self, costmap: Costmap, start: tuple[float, float, float], goal: tuple[float, float],
              table: NDArray[np.float64], tolerance: float = 0.0,
              guide: NDArray[np.float64] | None = None) -> Se2Search | Se2Plan:
        """The search set up (window, collision grids, heuristic) but not run — ``advance`` runs it in slices —
        or the failed plan when no search is needed to know there is no route."""
        t0 = time.perf_counter()
        cfg, res = self.cfg, costmap.resolution
        self._res = res
        pts = np.array([start[:2], goal[:2]], dtype=float)
        if guide is not None and len(guide):
            pts = np.vstack([pts, guide])
        scol, srow = (int(v) for v in costmap.world_to_cell(start[0], start[1]))
        gcol, grow = (int(v) for v in costmap.world_to_cell(goal[0], goal[1]))
        if not (costmap.in_bounds(scol, srow) and costmap.in_bounds(gcol, grow)):
            return Se2Plan(False, reason="start or goal is off the costmap")
        margin = cfg.window_margin
        while True:
            win = self._window(costmap, pts, margin)
            blocked = self.blocked_grids(costmap, win)
            factor = self._factor(costmap, win, table)
            sr, sc, gr, gc = srow - win.r0, scol - win.c0, grow - win.r0, gcol - win.c0
            h, goals = self._heuristic(blocked, factor, (sr, sc), (gr, gc), int(math.floor(tolerance / res)))
            if len(goals) == 0:
                return Se2Plan(False, reason="no heading fits the footprint at or near the goal",
                               seconds=time.perf_counter() - t0)
            if math.isfinite(h[sr, sc]):
                break
            # cut off inside the window: a detour may lie outside it, so look wider while that is affordable
            bigger = self._window(costmap, pts, 2 * margin + res)
            whole = bigger.shape == win.shape
            if whole or bigger.shape[0] * bigger.shape[1] > cfg.max_window_cells:
                return Se2Plan(False, reason="no footprint-feasible route: the goal is cut off at every heading "
                               f"within {margin:.1f} m of the 2D path", seconds=time.perf_counter() - t0)
            margin = 2 * margin + res
        goal_mask = np.zeros(win.shape, np.bool_)
        goal_mask.flat[goals] = True
        sbin = int(round((start[2] % math.pi) / (math.pi / cfg.bins))) % cfg.bins
        exact = bool(goal_mask[gr, gc]) if 0 <= gr < win.shape[0] and 0 <= gc < win.shape[1] else False
        grid = _GridFrame(costmap.origin_x, costmap.origin_y, res)
        return Se2Search(self, grid, win, blocked, factor, h, goal_mask, (sbin * win.shape[0] + sr) * win.shape[1]
                         + sc, start, goal, exact, time.perf_counter() - t0)

    def _factor(self, costmap: Costmap, win: _Window, table: NDArray[np.float64]) -> NDArray[np.float32]:
        """Traversal factor per window cell: the 2D table's, with the inscribed band charged like the costliest
        free cell (the collision grids decide where the rectangle fits) and unknown as free space."""
        t = np.asarray(table, dtype=np.float64).copy()
        top = float(t[MAX_NON_OBSTACLE])
        t[~np.isfinite(t)] = top
        t[LETHAL] = np.inf
        if not np.isfinite(table[NO_INFORMATION]):
            t[NO_INFORMATION] = top
        return t[costmap.costs[win.r0:win.r1, win.c0:win.c1]].astype(np.float32)

    @staticmethod
    def _goal_cells(passable: NDArray[np.bool_], gr: int, gc: int, k: int) -> NDArray[np.int64]:
        """The goal cell if some heading fits there, else the passable cells within ``k`` cells, nearest first."""
        rows, cols = passable.shape
        r0, r1, c0, c1 = max(0, gr - k), min(rows, gr + k + 1), max(0, gc - k), min(cols, gc + k + 1)
        rr, cc = np.mgrid[r0:r1, c0:c1]
        d2 = (rr - gr) ** 2 + (cc - gc) ** 2
        ok = (d2 <= k * k) & passable[r0:r1, c0:c1]
        if ok[min(gr - r0, ok.shape[0] - 1), min(gc - c0, ok.shape[1] - 1)] and d2[gr - r0, gc - c0] == 0:
            return np.array([gr * cols + gc], np.int64)
        order = np.argsort(d2[ok], kind="stable")
        return (rr[ok] * cols + cc[ok])[order].astype(np.int64)

    def extract_path(self, costmap: _GridFrame, win: _Window, parent: NDArray[np.int64], found: int,
                 start: tuple[float, float, float], goal: tuple[float, float],
                 exact_goal: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """World points and headings from the start to the found state; a turn in place keeps one point
        (with the heading after the turn), and the path is densified to the costmap resolution."""
        states = []
        s = found
        while s >= 0:
            states.append(s)
            s = int(parent[s])
        st = np.array(states[::-1], np.int64)
        rows, cols = win.shape
        b, rem = st // (rows * cols), st % (rows * cols)
        r, c = rem // cols + win.r0, rem % cols + win.c0
        x, y = costmap.origin_x + (c + 0.5) * costmap.resolution, costmap.origin_y + (r + 0.5) * costmap.resolution
        yaw = b * math.pi / self.cfg.bins
        last = np.ones(len(st), bool)
        last[:-1] = (r[1:] != r[:-1]) | (c[1:] != c[:-1])    # the last state of each run at one cell
        first = np.ones(len(st), bool)
        first[1:] = last[:-1]                                 # the first state of each run
        pts = np.column_stack([x, y])[last]
        pts[0] = start[:2]
        if exact_goal:
            pts[-1] = goal[:2]
        return _densify(pts, yaw[first], yaw[last], costmap.resolution)


@dataclass(frozen=True)
class _GridFrame:
    """Where the costmap's cells were when a search began (the map may grow or move while it runs)."""

    origin_x: float
    origin_y: float
    resolution: float


class Se2Search:
    """One lattice search, run in slices of expansions (``advance``), so a control loop that plans inside its
    tick can give it a bounded share of each tick. It searches the grids as they were when it began; the
    navigator checks the result against the current ones at the next replan, like any kept path."""

    def __init__(self, planner: Se2Planner, frame: _GridFrame, win: _Window, blocked: NDArray[np.bool_],
                 factor: NDArray[np.float32], h: NDArray[np.float64], goal_mask: NDArray[np.bool_], s_state: int,
                 start: tuple[float, float, float], goal: tuple[float, float], exact_goal: bool,
                 seconds: float) -> None:
        self.planner, self.frame, self.win = planner, frame, win
        self.blocked, self.factor, self.h, self.goal_mask = blocked, factor, h, goal_mask
        self.start, self.goal, self.exact_goal, self.s_state = start, goal, exact_goal, s_state
        self.seconds, self.expansions = seconds, 0
        n = blocked.size
        self.g, self.parent = np.full(n, np.inf, np.float32), np.full(n, -1, np.int32)
        self.closed = np.zeros(n, np.bool_)
        self.hk, self.hv = np.empty(1 << 16), np.empty(1 << 16, np.int64)
        self.size = np.zeros(1, np.int64)
        self.g[s_state] = 0.0
        sr, sc = (s_state % (win.shape[0] * win.shape[1])) // win.shape[1], s_state % win.shape[1]
        self.size[0] = _se2_search.heap_push(self.hk, self.hv, 0, planner.cfg.heuristic_weight * h[sr, sc],
                                             np.int64(s_state))

    def advance(self, budget: int) -> Se2Plan | None:
        """Expand up to ``budget`` more states (never past ``max_expansions`` in all); the plan once the search
        ended, None while it goes on."""
        t0 = time.perf_counter()
        cfg = self.planner.cfg
        budget = min(budget, cfg.max_expansions - self.expansions)
        res = self.frame.resolution
        rot = cfg.rotation_cost * (math.pi / cfg.bins) / res     # metres → cells
        esc = cfg.escape_radius / res
        found = -3
        while found == -3 and budget > 0:
            found, n = _se2_search.lattice_astar(
                self.blocked, self.factor, self.h, self.s_state, self.goal_mask, rot, cfg.heuristic_weight,
                esc * esc, 4.0, budget, self.g, self.parent, self.closed, self.hk, self.hv, self.size)
            self.expansions += n
            budget -= n
            if found == -3:
                self.hk = np.concatenate([self.hk, np.empty_like(self.hk)])
                self.hv = np.concatenate([self.hv, np.empty_like(self.hv)])
        self.seconds += time.perf_counter() - t0
        if found >= 0:
            path, headings = self.planner.extract_path(self.frame, self.win, self.parent, found, self.start, self.goal,
                                                   self.exact_goal)
            length = float(np.sum(np.hypot(*np.diff(path, axis=0).T))) if len(path) > 1 else 0.0
            return Se2Plan(True, path, headings, "", length, self.expansions, self.seconds)
        if found == -1:
            return Se2Plan(False, reason="no route the footprint fits through at any heading",
                           expansions=self.expansions, seconds=self.seconds)
        if self.expansions >= cfg.max_expansions:
            return Se2Plan(False, reason="gave up after max_expansions states", expansions=self.expansions,
                           seconds=self.seconds)
        return None


def _densify(pts: NDArray[np.float64], arrive: NDArray[np.float64], leave: NDArray[np.float64],
             spacing: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points ≤ spacing apart. Point i is reached holding ``arrive[i]`` (a translation keeps its bin, so the
    points inserted before it hold that heading too) and left holding ``leave[i]`` after any turn in place;
    the heading listed for point i itself is ``leave[i]``, the one to hold from there on."""
    if len(pts) < 2:
        return pts.copy(), leave.copy()
    out, hs = [pts[:1]], [leave[:1]]
    for i in range(1, len(pts)):
        a, b = pts[i - 1], pts[i]
        n = max(1, int(math.ceil(float(np.hypot(*(b - a))) / spacing - 1e-9)))
        t = (np.arange(1, n + 1) / n)[:, None]
        out.append(a + t * (b - a))
        hs.append(np.append(np.full(n - 1, arrive[i]), leave[i]))
    return np.vstack(out), np.concatenate(hs)
