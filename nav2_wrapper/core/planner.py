"""Global planner: cost-aware 8-connected A* on the costmap, goal tolerance, Theta*-style shortcutting.

Traversal cost of a cell is ``1 + cost_travel_multiplier * cost / 252`` per unit length (Smac-2D-like);
inscribed and lethal cells are blocked, unknown cells cost like ``unknown_cost`` when ``allow_unknown``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_common.params import param

from . import _search
from .costmap import Costmap
from .costs import INSCRIBED, LETHAL, MAX_NON_OBSTACLE, NO_INFORMATION
from .se2_planner import Se2PlannerConfig

SQRT2 = math.sqrt(2.0)


@dataclass
class PlannerConfig:
    """The planner plugin's parameters (``planner_server.<plugin>`` in a params profile)."""

    tolerance: float = param(0.5, "accept the nearest reachable cell this close to a blocked goal", unit="m", ge=0)
    allow_unknown: bool = param(True, "plan through unknown cells (charged at unknown_cost)")
    cost_travel_multiplier: float = param(
        2.0, "traversal cost per unit length is 1 + multiplier * cost / 252 (0: shortest path)", ge=0)
    unknown_cost: int = param(200, "cost an unknown cell is charged at", ge=0, le=252)
    smooth_path: bool = param(True, "shortcut the grid path Theta*-style where the straight line costs no more")
    smoothing_slack: float = param(
        0.02, "a shortcut may cost this fraction more than the sub-path it replaces", ge=0)
    escape_radius: float = param(0.35, "how far a start inside the inscribed band may move through it", unit="m",
                                 ge=0)
    heuristic_weight: float = param(
        1.0, "weighted A*: path cost <= weight * optimal (1: cost-optimal, what every robot profile uses)", ge=1.0)
    bucket_width: float = param(
        0.5, "f range of one bucket of the search's queue (cells x traversal factor); the path cost is exact "
             "whatever the width, only the speed changes", gt=0, le=16.0)
    se2: Se2PlannerConfig = field(default_factory=Se2PlannerConfig)   # the footprint-aware fallback (se2_* keys)


@dataclass
class PlanResult:
    ok: bool
    path: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))  # (N, 2) world points
    reason: str = ""
    cost: float = 0.0                   # A* cost (cells × traversal factor)
    length: float = 0.0                 # m, of the returned path
    expansions: int = 0
    headings: NDArray[np.float64] | None = None   # per path point (rad): set when the SE(2) fallback planned it
    cells: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 2), np.int64))  # grid path (row, col)


class GlobalPlanner:
    """Plans on a Costmap's master costs. Holds search buffers so repeated plans allocate nothing big."""

    def __init__(self, cfg: PlannerConfig | None = None) -> None:
        self.cfg = cfg or PlannerConfig()
        self._size = 0
        self._stamp = 0

    def traversal_table(self) -> NDArray[np.float64]:
        c = self.cfg
        t = 1.0 + c.cost_travel_multiplier * np.arange(256, dtype=np.float64) / MAX_NON_OBSTACLE
        t[INSCRIBED] = t[LETHAL] = np.inf
        t[NO_INFORMATION] = (1.0 + c.cost_travel_multiplier * min(c.unknown_cost, MAX_NON_OBSTACLE) / MAX_NON_OBSTACLE
                             if c.allow_unknown else np.inf)
        return t

    def _buffers(self, n: int) -> None:
        """An 8-byte search record per cell (see ``_search``), reused between plans via stamps."""
        if n != self._size:
            self._rec = np.zeros(2 * n, np.int32)
            self._size, self._stamp = n, 0
        self._next_stamp()

    def _next_stamp(self) -> None:
        self._stamp += 1
        if self._stamp >= 2 ** (31 - _search.STATE_SHIFT) - 1:     # the state word stays a positive int32
            self._rec[:] = 0
            self._stamp = 1

    def plan(self, costmap: Costmap, start: tuple[float, float], goal: tuple[float, float]) -> PlanResult:
        """Path from start to goal (world x, y in the costmap frame), or ok=False with the reason."""
        costs = costmap.costs
        rows, cols = costs.shape
        res = costmap.resolution
        sc, sr = (int(v) for v in costmap.world_to_cell(start[0], start[1]))
        gc, gr = (int(v) for v in costmap.world_to_cell(goal[0], goal[1]))
        if not costmap.in_bounds(sc, sr):
            return PlanResult(False, reason=f"start ({start[0]:.2f}, {start[1]:.2f}) is off the costmap")
        if not costmap.in_bounds(gc, gr):
            return PlanResult(False, reason=f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is off the costmap")
        table = self.traversal_table()
        self._buffers(rows * cols)
        s_flat, g_flat = sr * cols + sc, gr * cols + gc
        target = g_flat
        candidates = None           # only needed when the goal cell is blocked or out of reach
        if not np.isfinite(table[costs[gr, gc]]):
            candidates = self._goal_candidates(costs, table, gr, gc, res)
            if len(candidates) == 0:
                return PlanResult(False, reason=self._blocked_reason(costs[gr, gc], goal))
            target = int(candidates[0])
        esc_r2 = (self.cfg.escape_radius / res) ** 2
        esc_cost = 1.0 + self.cfg.cost_travel_multiplier * 2.0
        found, expansions = self._search(costs, table, s_flat, target, esc_r2, esc_cost)
        if not found:
            # The failed search closed the start's whole component: take the nearest closed candidate.
            if candidates is None:
                candidates = self._goal_candidates(costs, table, gr, gc, res)
            reach = [int(c) for c in candidates if _search.closed(self._rec, int(c), self._stamp)]
            if not reach:
                why = self._blocked_reason(costs[gr, gc], goal) if not np.isfinite(table[costs[gr, gc]]) else (
                    f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is not reachable from the start "
                    f"(searched {expansions} cells, tolerance {self.cfg.tolerance:.2f} m)")
                return PlanResult(False, reason=f"no path: {why}", expansions=expansions)
            target = reach[0]
        cells, gvals = _search.backtrack(self._rec, cols, s_flat, target)
        total = float(gvals[-1])
        grid_path = np.stack([cells // cols, cells % cols], axis=1)
        if self.cfg.smooth_path and len(cells) > 2:
            keep = _search.shortcut(costs, table, cells, gvals, self.cfg.smoothing_slack)
            cells = cells[keep]
        x, y = costmap.cell_to_world(cells % cols, cells // cols)
        pts = np.stack([x, y], axis=1)
        pts[0] = start
        if target == g_flat:
            pts[-1] = goal
        dense = densify(pts, res)
        length = float(np.sum(np.hypot(*np.diff(dense, axis=0).T))) if len(dense) > 1 else 0.0
        return PlanResult(True, dense, "", total, length, expansions, cells=grid_path)

    def _search(self, costs: NDArray[np.uint8], table: NDArray[np.float64], start: int, target: int,
                esc_r2: float, esc_cost: float) -> tuple[bool, int]:
        """(found, expansions) of the search from ``start`` to ``target``; on failure every cell reachable from the
        start is closed in the record."""
        h_scale = min(float(np.min(table)), esc_cost)      # the cheapest move per unit length keeps h admissible
        finite = table[np.isfinite(table)]
        max_step = SQRT2 * max(float(finite.max()) if len(finite) else 1.0, esc_cost)
        width = self.cfg.bucket_width
        weight = self.cfg.heuristic_weight
        found, expansions = _search.astar(costs, table, start, target, self._rec, self._stamp, esc_r2, esc_cost,
                                          weight, h_scale, width, _search.ring_size(width, max_step, weight, h_scale))
        return bool(found), int(expansions)

    def _goal_candidates(self, costs: NDArray[np.uint8], table: NDArray, gr: int, gc: int, res: float) -> NDArray:
        """Traversable cells within ``tolerance`` of the goal cell, nearest first (flat indices)."""
        rows, cols = costs.shape
        k = int(math.floor(self.cfg.tolerance / res))
        r0, r1, c0, c1 = max(0, gr - k), min(rows, gr + k + 1), max(0, gc - k), min(cols, gc + k + 1)
        rr, cc = np.mgrid[r0:r1, c0:c1]
        d2 = (rr - gr) ** 2 + (cc - gc) ** 2
        ok = (d2 <= k * k) & np.isfinite(table[costs[r0:r1, c0:c1]])
        order = np.argsort(d2[ok], kind="stable")
        return (rr[ok] * cols + cc[ok])[order]

    def _blocked_reason(self, cost: int, goal: tuple[float, float]) -> str:
        what = {LETHAL: "in an obstacle", INSCRIBED: "too close to an obstacle",
                NO_INFORMATION: "in unknown space (allow_unknown is false)"}.get(int(cost), "blocked")
        return (f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is {what} and no free cell lies within "
                f"tolerance {self.cfg.tolerance:.2f} m")


def densify(pts: NDArray[np.float64], spacing: float) -> NDArray[np.float64]:
    """Insert points so consecutive ones are ≤ spacing apart (controllers expect dense Nav2-style paths)."""
    if len(pts) < 2:
        return pts.copy()
    return _search.densify(np.ascontiguousarray(pts, dtype=np.float64), float(spacing))


def path_length(path: NDArray[np.float64]) -> float:
    return float(np.sum(np.hypot(*np.diff(path, axis=0).T))) if len(path) > 1 else 0.0
