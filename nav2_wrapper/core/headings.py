"""Headings for a planned path, checked with the true footprint.

The global planner searches (x, y) for a disc of the inscribed radius, which is right for where the centre
may go but says nothing about how a 0.70 × 0.50 m rectangle must be turned to get through. This module
assigns a heading to every point of such a path by dynamic programming over heading bins: a bin is allowed
at a point only if the footprint outline at that pose touches no lethal cell, consecutive points may differ
by at most the rotation the base can make while covering the distance between them, and among the feasible
assignments the one that turns least and stays closest to the path direction wins (the body's front and
back are interchangeable, so headings live modulo a half turn).

The result either gives the heading profile (which the controller can hold through a tight spot) or the
first point where no heading fits, which the navigator turns into a keep-out for the next plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .costmap import Costmap
from .costs import LETHAL


@dataclass(frozen=True)
class HeadingConfig:
    """How finely headings are searched and how much turning is allowed between path points."""

    bins: int = 36                  # over a half turn: 5° per bin
    spacing: float = 0.1            # m between the path points that get a heading
    max_turn_per_m: float = 4.0     # rad of rotation allowed per metre travelled (1.9 rad/s at 0.5 m/s ≈ 3.8)
    tangent_weight: float = 0.3     # cost per rad of deviation from the path direction
    outline_spacing: float = 0.05   # m between footprint outline points checked


@dataclass
class HeadingPlan:
    """Headings (rad) at ``points``; ``blocked`` is the index of the first point no heading fits (or None)."""

    points: NDArray[np.float64]
    headings: NDArray[np.float64]
    blocked: int | None

    @property
    def feasible(self) -> bool:
        return self.blocked is None


def resample(path: NDArray[np.float64], spacing: float) -> NDArray[np.float64]:
    """Points along a polyline every ``spacing`` m (first and last point kept)."""
    path = np.asarray(path, dtype=float).reshape(-1, 2)
    if len(path) < 2:
        return path.copy()
    seg = np.hypot(*np.diff(path, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    if cum[-1] <= 1e-9:
        return path[:1].copy()
    s = np.append(np.arange(0.0, cum[-1], spacing), cum[-1])
    return np.column_stack([np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])])


def _tangents(points: NDArray[np.float64]) -> NDArray[np.float64]:
    if len(points) < 2:
        return np.zeros(len(points))
    d = np.gradient(points, axis=0)
    return np.arctan2(d[:, 1], d[:, 0])


def _half_turn_diff(a: NDArray[np.float64], b: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """|a − b| modulo a half turn, in [0, π/2]."""
    d = np.mod(np.asarray(a) - b, math.pi)
    return np.minimum(d, math.pi - d)


def feasible_bins(points: NDArray[np.float64], costmap: Costmap, outline: NDArray[np.float64],
                  bins: int) -> NDArray[np.bool_]:
    """(N, bins): whether the footprint at each point and bin heading touches no lethal cell."""
    yaws = np.arange(bins) * math.pi / bins
    poses = np.column_stack([np.repeat(points[:, 0], bins), np.repeat(points[:, 1], bins), np.tile(yaws, len(points))])
    fc = costmap.footprint_costs(poses, outline, outside=0)
    return ~(fc == LETHAL).any(axis=1).reshape(len(points), bins)


def assign_headings(path: NDArray[np.float64], costmap: Costmap, outline: NDArray[np.float64],
                    cfg: HeadingConfig | None = None, start_yaw: float | None = None) -> HeadingPlan:
    """The least-turning feasible heading profile along ``path`` (see the module docstring)."""
    cfg = cfg or HeadingConfig()
    pts = resample(path, cfg.spacing)
    if len(pts) == 0:
        return HeadingPlan(pts, np.zeros(0), None)
    return headings_over(pts, feasible_bins(pts, costmap, outline, cfg.bins), cfg, start_yaw)


def headings_over(pts: NDArray[np.float64], ok: NDArray[np.bool_], cfg: HeadingConfig,
                  start_yaw: float | None = None) -> HeadingPlan:
    """The dynamic programme of :func:`assign_headings` on given points and an (N, bins) feasibility matrix,
    for callers with their own collision model (the SE(2) planner's grown-footprint grids)."""
    n, k = ok.shape
    ok = ok.copy()
    if start_yaw is not None:
        ok[0] = False
        ok[0, int(round((start_yaw % math.pi) / (math.pi / k))) % k] = True   # the body is where it is
    yaws = np.arange(k) * math.pi / k
    step = math.pi / k
    reach = max(1, int(math.ceil(cfg.max_turn_per_m * cfg.spacing / step)))
    dev = cfg.tangent_weight * _half_turn_diff(yaws[None, :], _tangents(pts)[:, None])
    cost = np.where(ok[0], dev[0], np.inf)
    if not np.isfinite(cost).any():
        return HeadingPlan(pts, np.zeros(0), 0)
    back = np.zeros((n, k), dtype=np.int32)
    shifts = np.arange(-reach, reach + 1)
    turn_cost = np.abs(shifts) * step
    for i in range(1, n):
        # for every bin, the best predecessor within ``reach`` bins (cyclic: headings wrap at a half turn)
        cand = np.stack([np.roll(cost, s) for s in shifts]) + turn_cost[:, None]
        best = np.argmin(cand, axis=0)
        new = cand[best, np.arange(k)] + dev[i]
        back[i] = (np.arange(k) - shifts[best]) % k
        cost = np.where(ok[i], new, np.inf)
        if not np.isfinite(cost).any():
            return HeadingPlan(pts, np.zeros(0), i)
    idx = np.empty(n, dtype=np.int32)
    idx[-1] = int(np.argmin(cost))
    for i in range(n - 1, 0, -1):
        idx[i - 1] = back[i, idx[i]]
    return HeadingPlan(pts, yaws[idx], None)
