"""Footprint-aware global planning: the 2D plan, checked for headings, with the SE(2) search as a fallback.

The 2D planner is fast and right wherever the rectangle fits the path at some heading, which is nearly always;
the heading assignment (``headings``) tells cheaply whether that is so. It is run on the SE(2) search's own
collision model — the footprint grown by the search's margin — not on the bare outline: a path the bare outline
passes with millimetres to spare is one the robot wedges on (clutter world 41: the bare check accepts a 13 m
route, the configuration-space proof's shortest route with 5 cm clearance is 15.4 m). Only when some point of
the 2D path has no such heading does the (x, y, heading) lattice search run: a route through a
gap the inscribed disc fits but the rectangle does not must be replaced by a different route, not by a keep-out
patch on the same one. If the lattice search fails too (e.g. the map is still mostly unknown, or the window is
too small), the 2D path is kept: the controller's own footprint checks and the recoveries still apply, and the
next replan sees more of the map.

The search's result is kept between replans: at the next (1 Hz) replan, when the 2D path still has a point
without a fitting heading, the rest of the previous SE(2) path — from the pose nearest the robot on, each pose
at its own heading — is looked up in the current collision grids, and if every pose still fits it is kept
instead of searching again; if some pose no longer fits at its own heading (the map grew, a noise speckle),
the heading assignment is run along the kept route, as for a 2D path, and new headings that fit keep it too.
A search costs up to seconds; the lookup costs what the heading check of the 2D path costs. A 2D path that
fits is still preferred (it follows map changes for free).

Tight spots are remembered for the goal. A gap seen from afar through a noisy map often looks wide enough and
turns out too narrow from close by; the robot then takes the detour, backs away, the gap looks passable again
and the plan flips back (clutter world 14 with sensor noise: 120 s of shuttling between a 4.5 m route and a
10 m detour, never arriving). So the point where the heading check failed is kept with the distance it was
judged from (the closest, if found again), and is lethal in the grids the check, the reuse test and the search
see while the robot is farther away than that. Back about as close, the map is first-hand again and decides: a
fitting path through the spot then clears it.
"""

from __future__ import annotations

import copy
import math
import statistics
import time
from dataclasses import dataclass, field, replace

import numpy as np

from robonix_common.geometry import Pose2D

from .costmap import Costmap
from .costs import LETHAL
from .footprint import Footprint
from .headings import HeadingConfig, headings_over, resample
from .planner import GlobalPlanner, PlanResult
from .se2_planner import Se2Plan, Se2Planner, Se2Search


@dataclass
class FallbackStats:
    """What the SE(2) fallback did so far (for benches and logs): wall seconds of each run and their outcome."""

    runs: int = 0
    found: int = 0
    reuses: int = 0
    reheaded: int = 0              # of the reuses, those that needed new headings somewhere
    slice_max_s: float = 0.0       # the longest single call into the search (set-up + one slice): the stall
    tight_spots: int = 0           # points remembered as too narrow (see the module docstring)
    seconds: list[float] = field(default_factory=list)
    last: Se2Plan | None = None

    def summary(self) -> dict[str, float]:
        s = self.seconds
        return {"se2_runs": self.runs, "se2_found": self.found, "se2_reuses": self.reuses,
                "se2_reheaded": self.reheaded, "se2_slice_max_s": self.slice_max_s,
                "se2_tight_spots": self.tight_spots,
                "se2_median_s": statistics.median(s) if s else 0.0, "se2_max_s": max(s) if s else 0.0}


class FootprintAwarePlanner:
    """Wraps the 2D planner's result: heading check, then the SE(2) fallback where no heading fits."""

    def __init__(self, planner: GlobalPlanner, footprint: Footprint) -> None:
        self.planner = planner
        self.se2 = Se2Planner(planner.cfg.se2, footprint)
        # the 2D path is checked with the SE(2) search's own collision model (grown footprint, same bins), at
        # half the costmap cells' spacing of the usual heading assignment
        self.headings_cfg = HeadingConfig(bins=planner.cfg.se2.bins, spacing=0.05)
        self.stats = FallbackStats()
        self._kept: _KeptPath | None = None
        self._spots: list[_TightSpot] = []
        self._pending: tuple[Se2Search, PlanResult, tuple[float, float]] | None = None

    def refine(self, costmap: Costmap, pose: Pose2D, goal: tuple[float, float], res: PlanResult,
               budget: int | None = None) -> PlanResult | None:
        """``res`` itself when the footprint fits along it at some heading everywhere (or the fallback is off),
        else the kept or a new SE(2) path with its headings, else ``res`` again (see the module docstring).
        With a ``budget`` (expansions), a search that needs more returns None and goes on in ``advance``."""
        cfg = self.planner.cfg
        if not cfg.se2.enabled or not res.ok or len(res.path) < 2:
            return res
        real, costmap = costmap, self._with_spots(costmap, pose)
        pts = resample(res.path, self.headings_cfg.spacing)
        ok = self.se2.feasible_bins(costmap, pts)
        # where the body is now it already fits (a grown-footprint overlap there is the margin, not a wedge):
        # the search would only escape from it, so it is no reason to replace the plan
        ok[np.hypot(pts[:, 0] - pose[0], pts[:, 1] - pose[1]) <= cfg.se2.escape_radius] = True
        check = headings_over(pts, ok, self.headings_cfg)
        if check.feasible:
            self._kept = None
            self._cleared(pts, pose)
            return res
        tight = pts[check.blocked]
        if not self.se2.feasible_bins(real, tight[None]).any():  # too narrow in the map itself, not a turn-rate limit
            self._remember(tight, pose)                            # nor a remembered spot's lethal disc
        kept = self._still_valid(costmap, pose, goal)
        if kept is not None:
            self.stats.reuses += 1
            return replace(res, path=kept[0], headings=kept[1], length=_length(kept[0]))
        self._kept = None
        t0 = time.perf_counter()
        search = self.se2.begin(costmap, (float(pose[0]), float(pose[1]), float(pose[2])), goal,
                                self.planner.traversal_table(), cfg.tolerance, guide=res.path)
        if isinstance(search, Se2Plan):
            return self._finish(search, res, goal)
        self._pending = (search, res, goal)
        return self.advance(budget, time.perf_counter() - t0)

    @property
    def pending(self) -> bool:
        """A search was begun and has not ended yet (``advance`` carries it on)."""
        return self._pending is not None

    def advance(self, budget: int | None = None, spent: float = 0.0) -> PlanResult | None:
        """Carry the pending search on by up to ``budget`` expansions (None: to its end); its outcome as in
        ``refine`` once it ended, None while it goes on. ``spent`` is this tick's set-up time, for the stats."""
        if self._pending is None:
            return None
        search, res, goal = self._pending
        t0 = time.perf_counter()
        plan = search.advance(self.se2.cfg.max_expansions if budget is None else budget)
        self.stats.slice_max_s = max(self.stats.slice_max_s, spent + time.perf_counter() - t0)
        if plan is None:
            return None
        return self._finish(plan, res, goal)

    def _finish(self, plan: Se2Plan, res: PlanResult, goal: tuple[float, float]) -> PlanResult:
        self._pending = None
        self.stats.runs += 1
        self.stats.seconds.append(plan.seconds)
        self.stats.last = plan
        if not plan.ok:
            return res
        self.stats.found += 1
        self._kept = _KeptPath((float(goal[0]), float(goal[1])), plan.path, np.asarray(plan.headings))
        return replace(res, path=plan.path, headings=np.asarray(plan.headings), length=plan.length,
                       expansions=res.expansions + plan.expansions)

    @property
    def tight_spots(self) -> tuple[tuple[float, float, float], ...]:
        """The remembered tight spots as (x, y, distance they were judged from)."""
        return tuple((sp.x, sp.y, sp.seen_from) for sp in self._spots)

    def forget(self) -> None:
        """Drop the kept SE(2) path, the tight spots and any pending search (a new goal, or the run ended)."""
        self._kept = None
        self._pending = None
        self._spots = []

    def _remember(self, point: np.ndarray, pose: Pose2D) -> None:
        """Keep a point where no heading fitted with the robot's distance now; a point within 0.3 m of a kept
        one is the same spot, which keeps the closest distance it was judged from."""
        x, y = float(point[0]), float(point[1])
        d = math.hypot(x - pose[0], y - pose[1])
        for i, sp in enumerate(self._spots):
            if math.hypot(sp.x - x, sp.y - y) < SPOT_MERGE:
                self._spots[i] = replace(sp, seen_from=min(sp.seen_from, d))
                return
        self._spots = [*self._spots, _TightSpot(x, y, d)][-MAX_SPOTS:]
        self.stats.tight_spots += 1

    def _near(self, sp: _TightSpot, pose: Pose2D) -> bool:
        """The robot is about as close as when the spot was found tight: the map there is first-hand again."""
        return math.hypot(sp.x - pose[0], sp.y - pose[1]) <= sp.seen_from + SPOT_RECHECK

    def _cleared(self, pts: np.ndarray, pose: Pose2D) -> None:
        """A path that fits runs through spots the robot is near again: they were a passing misjudgement."""
        self._spots = [sp for sp in self._spots if not (
            self._near(sp, pose) and np.min(np.hypot(pts[:, 0] - sp.x, pts[:, 1] - sp.y)) < SPOT_MERGE)]

    def _with_spots(self, costmap: Costmap, pose: Pose2D) -> Costmap:
        """The costmap with a lethal disc at each remembered spot the robot is not near (the costmap itself when
        there is none); only the cost array is copied, the caller's costmap is never changed."""
        spots = [sp for sp in self._spots if not self._near(sp, pose)]
        if not spots:
            return costmap
        out = copy.copy(costmap)
        out.costs = costmap.costs.copy()
        res = costmap.resolution
        r = int(math.ceil(SPOT_RADIUS / res))
        dr, dc = np.mgrid[-r:r + 1, -r:r + 1]
        disc = np.hypot(dr, dc) * res <= SPOT_RADIUS
        rows, cols = costmap.shape
        for sp in spots:
            col, row = (int(v) for v in costmap.world_to_cell(sp.x, sp.y))
            rr, cc = row + dr[disc], col + dc[disc]
            inside = (rr >= 0) & (rr < rows) & (cc >= 0) & (cc < cols)
            out.costs[rr[inside], cc[inside]] = LETHAL
        return out

    def _still_valid(self, costmap: Costmap, pose: Pose2D,
                     goal: tuple[float, float]) -> tuple[np.ndarray, np.ndarray] | None:
        """The rest of the kept SE(2) path from the robot on (path, headings) if it was planned to this goal,
        the robot is still near it, and every pose of it fits the current collision grids at its heading — or
        at headings the heading assignment finds anew along it."""
        kept, cfg = self._kept, self.planner.cfg.se2
        if kept is None or math.hypot(kept.goal[0] - goal[0], kept.goal[1] - goal[1]) > 1e-6:
            return None
        d = np.hypot(kept.path[:, 0] - pose[0], kept.path[:, 1] - pose[1])
        i = int(np.argmin(d))
        if d[i] > cfg.reuse_deviation or len(kept.path) - i < 2:
            return None
        path, headings = kept.path[i:].copy(), kept.headings[i:]
        path[0] = pose[0], pose[1]
        bins = np.round(np.mod(headings, math.pi) / (math.pi / cfg.bins)).astype(np.int64) % cfg.bins
        ok = self.se2.feasible_bins(costmap, path)
        ok[np.hypot(path[:, 0] - pose[0], path[:, 1] - pose[1]) <= cfg.escape_radius] = True
        if bool(ok[np.arange(len(path)), bins].all()):
            return path, headings
        # the map moved on (a post seen, a speckle): the route may still fit at other headings, which is the
        # test a 2D path passes; a search would most likely find this route again
        plan = headings_over(path, ok, self.headings_cfg)
        if not plan.feasible:
            return None
        self.stats.reheaded += 1
        return path, plan.headings


SPOT_RADIUS = 0.20      # m: the lethal disc a remembered spot gets (the found point wanders by a cell or two)
SPOT_MERGE = 0.3        # m: a new tight point this close to a remembered one is the same spot
SPOT_RECHECK = 0.5      # m: the map decides at a spot once the robot is within its distance plus this
MAX_SPOTS = 32          # per goal; the oldest go first


@dataclass(frozen=True)
class _TightSpot:
    """A path point where the footprint fitted at no heading, and how far from the robot it was judged."""

    x: float
    y: float
    seen_from: float


@dataclass
class _KeptPath:
    """The last SE(2) path found, with the goal it leads to."""

    goal: tuple[float, float]
    path: np.ndarray
    headings: np.ndarray


def _length(path: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(path, axis=0).T))) if len(path) > 1 else 0.0
