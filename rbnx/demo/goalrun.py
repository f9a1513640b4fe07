"""`rbnx demo`: one goal — send it, follow it to a terminal state with a live line, measure it against
the simulator's ground truth (path length, final error, collisions) and keep its plan for map.png."""

from __future__ import annotations

import math
import re
import threading
import time
from typing import Any

from rbnx.demo.boot import BootChild, DemoError
from rbnx.demo.goals import TERMINAL, fmt_s, parse_detail, path_length, warming_up
from rbnx.demo.record import Recorder
from rbnx.demo.report import GoalResult, LiveLine
from rbnx.demo.rpc import DemoRpc
from robonix_eval.clearance import ClearanceField

POLL_S = 0.3
MAX_NAV_EVENTS = 60
_NUMBERS = re.compile(r"[0-9]+(?:\.[0-9]+)?")


class GoalRunner:
    """Send one goal, follow it to a terminal state with a live line, measure it against ground truth."""

    def __init__(self, rpc: DemoRpc, rec: Recorder, boot: BootChild, stop: threading.Event,
                 timeout_s: float, line: LiveLine, clearance: ClearanceField | None = None) -> None:
        self.rpc, self.rec, self.boot, self.stop = rpc, rec, boot, stop
        self.timeout_s, self.line = timeout_s, line
        self.clearance = clearance

    def run(self, res: GoalResult, n: int) -> GoalResult:
        g = res.goal
        tag = f"goal {res.index}/{n} {g.name} ({g.x:.2f}, {g.y:.2f})"
        gt_mark, plan_mark = self.rec.mark()
        gt0 = self.rec.sample()
        t0 = time.monotonic()
        accepted, res.run_id, res.detail = self.rpc.navigate(g)
        if not accepted:
            res.state = "REJECTED"
            self.line.done(f"{tag}: REJECTED: {res.detail}")
            return res
        st_state, errors = "PENDING", 0
        t_limit = t0
        while True:
            if not self.boot.running():
                raise DemoError(f"rbnx boot exited (code {self.boot.proc.returncode if self.boot.proc else '?'}) "
                                f"during {tag}", self.boot.log_tail())
            if self.stop.is_set():
                self.rpc.cancel(res.run_id)
                st_state, res.detail = "CANCELED", "interrupted by the user"
                break
            if time.monotonic() - t_limit > self.timeout_s:
                self.rpc.cancel(res.run_id)
                st_state, res.detail = "TIMEOUT", f"no result after {self.timeout_s:g} s wall (goal cancelled)"
                break
            try:
                st = self.rpc.status(res.run_id)
                errors = 0
            except DemoError as exc:
                errors += 1
                if errors >= 10:
                    st_state, res.detail = "FAILED", f"status unavailable: {exc}"
                    break
                self.stop.wait(POLL_S)
                continue
            st_state, res.detail = st.state, st.detail
            if warming_up(st_state, res.detail):
                t_limit = time.monotonic()  # the per-goal timeout starts when the planner's warm-up ended
            self._note_status(res, st_state, res.detail)
            if st_state in TERMINAL:
                break
            self.line.update(st_state, self._progress(f"goal {res.index}/{n} {g.name}", st_state, res.detail, gt0, t0))
            self.stop.wait(POLL_S)
        res.state = st_state
        res.duration_wall_s = time.monotonic() - t0
        self._measure(res, gt0, gt_mark, plan_mark)
        err = f", {res.final_error_m:.2f} m from target" if res.final_error_m is not None else ""
        if res.collisions:
            err += f", {len(res.collisions)} contact(s): failed"
        self.line.done(f"{tag}: {res.outcome} in {fmt_s(res.duration_sim_s)} sim / {fmt_s(res.duration_wall_s)} "
                       f"wall{err} — {res.detail}")
        return res

    def _note_status(self, res: GoalResult, state: str, detail: str) -> None:
        """Keep a status whose wording (numbers aside) differs from the last one kept, stamped with the latest
        ground-truth sim time: the 'remaining' countdown collapses into one entry, a recovery or 'blocked'
        shows as its own."""
        kind = f"{state} {_NUMBERS.sub('#', detail)}"
        if (res.nav_events and res.nav_events[-1]["kind"] == kind) or len(res.nav_events) >= MAX_NAV_EVENTS:
            return
        last = self.rec.gt[-1] if self.rec.gt else None
        res.nav_events.append({"sim_time": round(last.sim_time, 3) if last is not None else None, "state": state,
                               "detail": detail, "kind": kind})

    def _contact_context(self, res: GoalResult) -> None:
        """Each contact with the robot's ground-truth pose just before it and the nav status then in force."""
        for c in res.collisions:
            p = self.rec.pose_before(c["sim_time"])
            if p is not None:
                c["robot_pose"] = {"sim_time": round(p[0], 3), "x": round(p[1], 3), "y": round(p[2], 3),
                                   "theta": round(p[3], 3)}
            before = [e for e in res.nav_events if e["sim_time"] is not None and e["sim_time"] <= c["sim_time"]]
            c["nav_detail"] = before[-1]["detail"] if before else ""

    def _progress(self, tag: str, state: str, detail: str, gt0: Any, t0: float) -> str:
        p = parse_detail(detail)
        if p.remaining_m is None:
            where = (detail or "waiting for the first status")[:60]
        else:
            where = f"{p.remaining_m:.2f} m left, ETA {p.eta_s:.0f}s sim"
        last = self.rec.gt[-1] if self.rec.gt else None
        sim = fmt_s(last.sim_time - gt0.sim_time) if (last is not None and gt0 is not None) else "-"
        extra = f", {p.recoveries} recoveries" if p.recoveries else ""
        blocked = ", blocked" if detail.endswith("blocked") else ""
        return f"{tag}: {state:<9} {where}{extra}{blocked} | elapsed sim {sim}, wall {fmt_s(time.monotonic() - t0)}"

    def _measure(self, res: GoalResult, gt0: Any, gt_mark: int, plan_mark: int) -> None:
        gt1 = self.rec.sample()
        end_gt, end_plan = self.rec.mark()
        samples = ([gt0] if gt0 is not None else []) + self.rec.gt_between(gt_mark + 1, end_gt)
        dense = self.rec.gt_path(gt0.sim_time, gt1.sim_time) if gt0 is not None and gt1 is not None else []
        res.path_length_m = path_length(dense if len(dense) >= 2 else [(s.x, s.y) for s in samples])
        if gt1 is not None:
            res.final_pose = (gt1.x, gt1.y, gt1.theta)
            res.final_error_m = math.hypot(gt1.x - res.goal.x, gt1.y - res.goal.y)
            if gt0 is not None:
                res.duration_sim_s = gt1.sim_time - gt0.sim_time
                if self.clearance is not None:
                    closest = self.clearance.closest(self.rec.gt_poses(gt0.sim_time, gt1.sim_time))
                    res.closest = closest.as_dict() if closest is not None else None
        if gt0 is not None:
            try:
                res.collisions = [c.as_dict() for c in self.rpc.collisions(gt0.sim_time)]
                self._contact_context(res)
            except DemoError as exc:
                self.rec.warnings.append(f"collisions: {exc}")
        plan = self.rec.plan_for(plan_mark, end_plan, (res.goal.x, res.goal.y))
        res.plan_length_m = path_length(plan.tolist()) if plan is not None else None
        res.plan = plan
