"""Speed limit state behind adjust_speed / set_speed_limit / get_speed_limit (``dynamic_speed`` config).

Two scopes, as in robonix: ``session`` (``persist=true``, or no run to attach to) holds until changed;
``goal`` applies to one run and falls back to the session value when that run ends. The effective
limit is a percentage of ``max_linear_speed_mps``, clamped to ``[min_percentage, 100]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .config import DynamicSpeed

FASTER, SLOWER, NORMAL = "faster", "slower", "normal"


@dataclass
class SpeedResult:
    accepted: bool
    changed: bool
    percentage: float
    mps: float
    scope: str
    run_id: str
    detail: str


class SpeedLimits:
    def __init__(self, cfg: DynamicSpeed, controller_max_mps: float) -> None:
        self.cfg = cfg
        self.max_mps = float(cfg.max_linear_speed_mps or controller_max_mps)
        self.session = float(cfg.default_percentage)
        self.goal_run = ""                 # run the goal-scoped override belongs to
        self.goal_pct: float | None = None

    def effective(self) -> tuple[float, str, str]:
        """(percentage, scope, run_id) currently in force."""
        if self.goal_pct is not None:
            return self.goal_pct, "goal", self.goal_run
        return self.session, "session", ""

    def mps(self, pct: float) -> float:
        return self.max_mps * pct / 100.0

    def run_ended(self, run_id: str) -> bool:
        """Drop a goal-scoped override of a finished run; True if the effective limit changed."""
        if self.goal_pct is not None and run_id == self.goal_run:
            changed = self.goal_pct != self.session
            self.goal_pct, self.goal_run = None, ""
            return changed
        return False

    def set(self, pct: float, run_id: str, persist: bool, active_run: str) -> SpeedResult:
        """``active_run`` = the running goal's id ("" when idle); a non-persistent limit attaches to it."""
        lo = self.cfg.min_percentage
        if not math.isfinite(pct) or pct < lo or pct > 100.0:
            cur, scope, rid = self.effective()
            return SpeedResult(False, False, cur, self.mps(cur), scope, rid,
                               f"percentage: {pct:g} is outside [{lo:g}, 100]")
        if run_id and run_id != active_run:
            cur, scope, rid = self.effective()
            why = "no run is active" if not active_run else f"the active run is {active_run}"
            return SpeedResult(False, False, cur, self.mps(cur), scope, rid,
                               f"run_id: {run_id!r} is not the active run ({why})")
        before = self.effective()[0]
        if persist or not active_run:
            self.session = float(pct)
            if persist:
                self.goal_pct, self.goal_run = None, ""
        else:
            self.goal_pct, self.goal_run = float(pct), active_run
        cur, scope, rid = self.effective()
        note = "" if persist or active_run else " (no active run: applied to the session)"
        return SpeedResult(True, cur != before, cur, self.mps(cur), scope, rid,
                           f"speed limit {cur:g}% = {self.mps(cur):.3f} m/s ({scope}){note}")

    def adjust(self, direction: str, run_id: str, persist: bool, active_run: str) -> SpeedResult:
        d = direction.strip().lower()
        cur = self.effective()[0]
        if d == FASTER:
            target = min(100.0, cur + self.cfg.step_percentage)
        elif d == SLOWER:
            target = max(self.cfg.min_percentage, cur - self.cfg.step_percentage)
        elif d == NORMAL:
            target = self.cfg.default_percentage
        else:
            scope_pct, scope, rid = self.effective()
            return SpeedResult(False, False, scope_pct, self.mps(scope_pct), scope, rid,
                               f"direction: {direction!r} is not one of faster, slower, normal")
        res = self.set(target, run_id, persist, active_run)
        if res.accepted and not res.changed:
            res.detail = f"already at the {'maximum' if d == FASTER else 'minimum' if d == SLOWER else 'default'}: " \
                         + res.detail
        return res
