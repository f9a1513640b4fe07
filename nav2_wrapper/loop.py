"""The running work of navigation: the control loop thread and the goal API around the Navigator.

One lock guards the navigator: gRPC/MCP handlers call ``navigate``/``cancel``/``status`` while the loop
ticks at the controller frequency on the provider's clock (sim time with ``use_sim_time``, so a
faster-than-real-time simulator gets the same control rate in sim seconds). The loop never hangs a
run, and never throws one away that could go on: when a required input (map→odom, odometry) is lost
(DDS liveliness, the atlas' TERMINATED notice, stale data) the robot is stopped at once and the run
paused (RUNNING, "waiting for mapping ..."); it continues when the input returns within
``input_grace_s`` and fails with the reason after that (``core/grace.py``). A lost optional input (the
lidar) only degrades the run. A provider missing from the atlas is not lost by itself: after an atlas
restart providers re-register, and the data plane decides. A stalled /clock stops the robot and fails
the run after ``clock_timeout_s``.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
import uuid
from dataclasses import dataclass
from typing import Any

import numpy as np

from nav2_wrapper import warmup_note
from nav2_wrapper.core import GoalRecord, Navigator
from nav2_wrapper.core.grace import FAILED as GRACE_FAILED
from nav2_wrapper.core.grace import PAUSED as GRACE_PAUSED
from nav2_wrapper.core.grace import InputGrace
from nav2_wrapper.core.latency import LatencyEstimate
from nav2_wrapper.core.navigator import FAILED, PENDING, RUNNING, TERMINAL
from nav2_wrapper.core.warmup import ready as kernels_ready
from nav2_wrapper.core.warmup import wait_finished as kernels_wait
from robonix_api.dds import FrameNotFoundError, Path, TfError, Twist
from robonix_api.dds.convert import header, pose_stamped, twist
from robonix_common.geometry import Pose2D, compose

from .config import ProviderConfig
from .goals import PlanarGoal
from .inputs import Inputs, RobotState
from .journal import GoalJournal, JournaledGoal
from .speed import SpeedLimits
from .tracing import GoalSpans
from .upstream import Binding, UpstreamWatch

log = logging.getLogger("nav2_wrapper.loop")
WAIT_SLICE_S = 0.1  # wall s: how often a waiting loop re-checks /clock stalls and stop requests
SELF_FREEZE_S = 1.0  # wall s after this process was frozen during which writers' liveliness losses are not trusted
WATCH_PERIOD_S = 1.0  # wall s between looks at the atlas (TERMINATED notices, re-registrations)
CLOCK_EPOCH_BACK_S = 1.0  # clock s /clock must go back to count as a new epoch (a restarted simulator)
LATENCY_LOG_S = 30.0  # clock s between the control-latency lines in the log while driving


@dataclass
class Publishers:
    cmd_vel: Any
    plan: Any | None


class NavLoop:
    def __init__(self, nav: Navigator, inputs: Inputs, pubs: Publishers, cfg: ProviderConfig, speed: SpeedLimits,
                 upstream: UpstreamWatch | None = None, journal: GoalJournal | None = None) -> None:
        self.nav, self.inputs, self.pubs, self.cfg, self.speed = nav, inputs, pubs, cfg, speed
        self.period = 1.0 / nav.cfg.navigator.controller_frequency
        self.lock = threading.RLock()
        self.accepting = False
        self._upstream = upstream
        self.journal = journal or GoalJournal(None)
        self._journaled = ""          # run id written to the journal ("" when none)
        self.grace = InputGrace(nav.cfg.navigator.input_grace_s)
        self._degraded = ""           # why an optional input is lost ("" when all are there)
        self._stop = threading.Event()
        self._grid_seq = self._scan_seq = 0
        self._plan_sent: Any = None
        self._state: RobotState | None = None
        self._tf_bad_since: float | None = None
        self._moving = False          # the last published command was non-zero
        self._sent = (0.0, 0.0, 0.0)  # the last published command: the base executes it until the next arrives
        self._clock_last = -math.inf
        self._clock_wall = time.monotonic()
        self._paused = False
        self._paused_zero_sent = False
        self._last_step_wall = time.monotonic()
        self._thawed_at = -math.inf
        self._spans = GoalSpans.maybe(cfg.frames.map)  # None unless tracing is on
        self.latency = LatencyEstimate()
        self._latency_seen: list[tuple[float, float]] = []   # (pose age, expected latency) since the last log line
        self._latency_logged = -math.inf
        self._thread = threading.Thread(target=self._run, name="nav-loop", daemon=True)
        self._watch = threading.Thread(target=self._watch_upstream, name="nav-upstream-watch", daemon=True)

    # ---- lifecycle ---------------------------------------------------------------------------------
    def warm_up(self) -> None:
        """Feed the first map and plan once, so the first goal does not pay for JIT loading (~0.3 s)."""
        with self.lock:
            grid, self._grid_seq = self.inputs.latest_grid(0)
            try:
                st = self.inputs.robot_state(self.inputs.clock.now())
            except TfError:
                return
            self.nav.tick(self.inputs.clock.now(), st.pose, st.vel, grid)
            x, y, _ = st.pose
            for dx, dy in ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)) if kernels_ready() else ():
                if self.nav.planner.plan(self.nav.global_costmap, (x, y), (x + dx, y + dy)).ok:
                    break
            self.nav.path = np.zeros((0, 2))

    def start(self) -> None:
        self._thread.start()
        if self._upstream is not None:
            self._watch.start()

    def set_accepting(self, on: bool, reason: str = "") -> None:
        """ACTIVATE (True) / DEACTIVATE (False: the running goal is canceled and the robot stopped)."""
        with self.lock:
            self.accepting = on
            if not on:
                self._end_active(reason or "canceled: navigation deactivated", canceled=True)
            else:
                self._resume_journaled()

    def _resume_journaled(self) -> None:
        """A previous process of ours died driving a goal: take it up again under its run id. Lock held."""
        g = self.journal.pending()
        if g is None or (self.nav.active is not None and self.nav.active.state not in TERMINAL):
            return
        rec = self.nav.navigate(g.x, g.y, g.yaw, self.inputs.clock.now(), run_id=g.run_id)
        if rec.accepted:
            self._journaled = g.run_id
            log.warning("resumed run %s from the goal journal (the previous process died driving it)", g.run_id)
        else:
            self.journal.clear()
            log.warning("goal journal's run %s not resumed: %s", g.run_id, rec.detail)

    def _sync_journal(self) -> None:
        """Keep the journal equal to the live run (cleared once it ended in any way). Lock held."""
        a = self.nav.active
        live = a.run_id if a is not None and a.state not in TERMINAL else ""
        if live == self._journaled:
            return
        if live:
            self.journal.record(JournaledGoal(live, *a.goal))
        else:
            self.journal.clear()
        self._journaled = live

    def stop(self, reason: str = "canceled: navigation shutting down") -> None:
        with self.lock:
            self.accepting = False
            self._end_active(reason, canceled=True)
            if self._spans is not None:
                self._spans.end_all()
        self._stop.set()
        for t in (self._thread, self._watch):
            if t.is_alive() and t is not threading.current_thread():
                t.join(5.0)
        if self._thread.ident is not None:  # never started (failed INIT): nothing was ever commanded
            self.publish_zero()

    def close(self, reason: str = "") -> None:
        """End of the session (``reason`` e.g. "re-initialized"): stop the loop, then the inputs and outputs."""
        self.stop(f"canceled: navigation {reason}" if reason else "canceled: navigation shutting down")
        self.inputs.close()
        for p in (self.pubs.cmd_vel, self.pubs.plan):
            if p is not None:
                p.close()

    # ---- goal API (handler threads) ----------------------------------------------------------------
    def navigate(self, goal: PlanarGoal | str, trace_parent: Any = None) -> tuple[GoalRecord | None, str]:
        """(record, preempted run_id or "").

        The record is None while not accepting goals (inactive); a rejected goal still gets a run_id
        and a FAILED record, so its status can be asked for like any other run. With tracing on, an
        accepted goal opens a span under ``trace_parent`` (the caller's trace context).
        """
        rid = f"nav-{uuid.uuid4().hex[:8]}"
        with self.lock:
            if not self.accepting:
                return None, ""
            now = self.inputs.clock.now()
            if isinstance(goal, str):
                return self._reject(rid, (math.nan, math.nan, math.nan), goal, now), ""
            xyz = self._to_map(goal)
            if isinstance(xyz, str):
                return self._reject(rid, (goal.x, goal.y, goal.yaw), xyz, now), ""
            prev = self.nav.active
            live = prev is not None and prev.state not in TERMINAL
            rec = self.nav.navigate(*xyz, now, run_id=rid)
            self._sync_journal()
            if rec.accepted and self._spans is not None:
                self._spans.start(rec, trace_parent, self._state.pose if self._state is not None else None)
                self._spans.sweep(None)  # a preempted run ends its span now
            if rec.accepted and live:
                self.speed.run_ended(prev.run_id)
                return rec, prev.run_id
            return rec, ""

    def cancel(self, run_id: str) -> tuple[GoalRecord | None, bool]:
        """(record, whether it was PENDING/RUNNING): a live run is CANCELED and the robot stopped at once."""
        with self.lock:
            rec = self.nav.status(run_id or None)
            if rec is None:
                return None, False
            was_live = rec.state not in TERMINAL
            if was_live:
                self.nav.cancel(self.inputs.clock.now(), rec.run_id)
                self._sync_journal()
                self.publish_zero()
                self.speed.run_ended(rec.run_id)
                if self._spans is not None:
                    self._spans.sweep(None)
            return rec, was_live

    def status(self, run_id: str) -> GoalRecord | None:
        with self.lock:
            return self.nav.status(run_id or None)

    def active_run(self) -> str:
        with self.lock:
            a = self.nav.active
            return a.run_id if a is not None and a.state not in TERMINAL else ""

    def remaining(self, rec: GoalRecord) -> float | None:
        """Metres left along the path of a RUNNING goal (None otherwise)."""
        with self.lock:
            if rec is not self.nav.active or rec.state != RUNNING or self._state is None:
                return None
            return self.nav.controller.remaining(self._state.pose)

    def apply_speed(self) -> None:
        """Hand the effective speed limit to the controller (after any change; also every tick)."""
        with self.lock:
            self.nav.set_speed_limit(self.speed.mps(self.speed.effective()[0]), percentage=False)

    # ---- helpers -----------------------------------------------------------------------------------
    def _reject(self, rid: str, goal: Pose2D, reason: str, now: float) -> GoalRecord:
        rec = GoalRecord(rid, goal, state=FAILED, detail=f"rejected: {reason}", accepted=False, started=now,
                         finished=now)
        self.nav.records[rid] = rec
        self.nav.latest = rec
        return rec

    def _to_map(self, g: PlanarGoal) -> Pose2D | str:
        mf = self.cfg.frames.map
        if g.frame in ("", mf):
            return g.x, g.y, g.yaw
        try:
            base = self.inputs.tf.lookup_pose2d(mf, g.frame)
        except FrameNotFoundError:
            return (f"goal.header.frame_id: unknown frame {g.frame!r} (use {mf!r}, or a TF frame connected "
                    f"to it; known: {', '.join(self.inputs.tf.frames()) or 'none'})")
        except TfError as exc:
            return f"goal.header.frame_id: cannot transform {g.frame!r} into {mf!r}: {exc}"
        p = compose(base, (g.x, g.y, g.yaw))
        return float(p[0]), float(p[1]), float(p[2])

    def _end_active(self, reason: str, canceled: bool) -> None:
        """Stop the running goal (CANCELED or FAILED with ``reason``) and the robot. Lock held."""
        rec = self.nav.active
        if rec is None or rec.state in TERMINAL:
            return
        self.nav.cancel(self.inputs.clock.now(), rec.run_id)
        self._sync_journal()
        if not canceled:
            rec.state = FAILED
        rec.detail = reason
        self.speed.run_ended(rec.run_id)
        self.publish_zero()
        if self._spans is not None:
            self._spans.sweep(None)
        log.info("run %s %s: %s", rec.run_id, rec.state, reason)

    def publish_zero(self) -> None:
        with contextlib.suppress(RuntimeError):  # closed during teardown
            self.pubs.cmd_vel.publish(twist(0.0, 0.0, 0.0))
        self._moving = False
        self._sent = (0.0, 0.0, 0.0)

    # ---- the loop ----------------------------------------------------------------------------------
    def _run(self) -> None:
        clock = self.inputs.clock
        due = clock.now()
        while not self._stop.is_set():
            if clock.use_sim_time:
                reached = clock.sleep_until(due, timeout=WAIT_SLICE_S)
            else:
                self._stop.wait(max(0.0, min(due - time.time(), WAIT_SLICE_S)))
                reached = time.time() >= due
            if self._stop.is_set():
                return
            now = clock.now()
            try:
                if clock.use_sim_time and now < self._clock_last - CLOCK_EPOCH_BACK_S:
                    self._new_clock_epoch(now)
                    due = now
                self._watch_clock(now)
                if reached and not kernels_wait(WAIT_SLICE_S):
                    self._note_warmup()
                    continue  # a cold numba compile is running: wait outside the lock (status stays answered)
                if reached:
                    self._step(now)
                    if self._spans is not None:
                        with self.lock:
                            self._spans.sweep(self._state.pose if self._state is not None else None)
                    due += self.period
                    if now > due + self.period:  # fell behind (slow machine): skip, do not burst
                        due = now + self.period
            except Exception:  # the loop must survive anything; the running goal is failed with the error
                log.exception("navigation loop iteration failed")
                with self.lock:
                    self._end_active("navigation loop error (see provider log)", canceled=False)
                self._stop.wait(0.05)

    def _new_clock_epoch(self, now: float) -> None:
        """/clock went back (a simulator started again from t = 0, e.g. without its saved state): every
        TF sample we hold is from another world, stamped in the new clock's future, and would look fresh.
        Drop them, stop the robot and fail the running goal: its progress cannot be judged from them (issue
        37: a goal was reported reached 7 m from the robot). The next goal starts on the new epoch's data."""
        old = self._clock_last
        log.warning("/clock went back from %.2f s to %.2f s (simulator restarted?): TF dropped, new clock epoch",
                    old, now)
        self.inputs.tf.clear(keep_static=True)
        self._clock_last, self._clock_wall = now, time.monotonic()
        self._state = None
        with self.lock:
            self._end_active(f"simulator restarted: /clock went back from {old:.1f} s to {now:.1f} s; the robot's "
                             "pose before and after cannot be compared", canceled=False)
            self.publish_zero()

    def _note_warmup(self) -> None:
        """A goal accepted while the planner warms up stays PENDING and says why (clients start their
        timeout when this note is gone: see nav2_wrapper.warmup_note)."""
        with self.lock:
            rec = self.nav.active
            if rec is not None and rec.state == PENDING:
                rec.detail = warmup_note.note()

    def _watch_clock(self, now: float) -> None:
        """Checks that must run even when sim time stands still: a /clock not advancing stops the robot at
        once and fails the run after clock_timeout_s (wall), or after input_grace_s (wall) when a required
        input is lost with it (the simulator itself died or stalled: the run waits for it by name)."""
        if not self.inputs.clock.use_sim_time:
            return
        wall = time.monotonic()
        if now > self._clock_last:
            self._clock_last, self._clock_wall = now, wall
            self._paused = False
            return
        stalled = wall - self._clock_wall
        with self.lock:
            rec = self.nav.active
            if rec is None or rec.state in TERMINAL:
                return
            if stalled <= self.cfg.clock_stall_s:
                return
            if not self._paused:
                self._paused = True
                self.publish_zero()
            lost, _ = self._inputs_lost(now, self._state)
            if lost:
                verdict = self.grace.update(now, wall, lost, clock_stalled=True)
                if verdict.state == GRACE_FAILED:
                    self._end_active(f"{verdict.detail}; /clock stalled for {stalled:.0f} s", canceled=False)
                else:
                    rec.detail = f"{verdict.detail}; /clock stalled for {stalled:.1f} s"
            elif stalled > self.cfg.clock_timeout_s:
                self._end_active(f"/clock stalled for {stalled:.0f} s (simulator stopped?)", canceled=False)
            else:
                rec.detail = f"paused: /clock stalled for {stalled:.1f} s; robot stopped"

    def _watch_upstream(self) -> None:
        """The atlas side of liveness: TERMINATED notices mark inputs lost; a provider that registered
        anew (restart) is looked up again and followed to its new topics. A provider merely missing from
        the atlas (the atlas restarted; providers re-register on their next heartbeat) changes nothing."""
        while not self._stop.wait(WATCH_PERIOD_S):
            try:
                terminated, rebinds = self._upstream.poll()
            except Exception as exc:  # atlas unreachable: not a reason to touch a run by itself
                log.debug("upstream check failed: %s", exc)
                continue
            for role in ("map", "odom", "scan"):
                self.inputs.set_terminated(role, terminated.get(role, ""))
            for role, b in rebinds.items():
                if role in ("map", "odom", "scan"):
                    self.inputs.rebind(role, b)
                elif role == "cmd_vel":
                    self._rebind_cmd_vel(b)

    def _rebind_cmd_vel(self, b: Binding) -> None:
        """Command the chassis on its new topic (it registered anew, e.g. restarted, elsewhere)."""
        new = self.inputs.node.create_publisher(b.topic, Twist, b.qos)
        with self.lock:
            old, self.pubs.cmd_vel = self.pubs.cmd_vel, new
            self.inputs.bindings["cmd_vel"] = b
        old.close()
        log.info("cmd_vel rebound to %s (provider %s)", b.topic, b.provider_id or "-")

    def _inputs_lost(self, now: float, state: RobotState | None) -> tuple[dict[str, str], dict[str, str]]:
        """{source: why} of lost required inputs and of lost optional ones (see ``Inputs.lost``)."""
        to = self.cfg.data_timeout_s
        wall = time.monotonic()
        # This process was frozen or starved (SIGSTOP, a swapped-out machine): every input looks old until
        # the samples queued meanwhile are read, so staleness waits one tick; liveliness still counts.
        # Likewise, our own DDS stack could not hear the writers' liveliness while frozen: their leases ran
        # out here, not there, and are renewed within a lease; so liveliness losses wait SELF_FREEZE_S too.
        fresh = wall - self._last_step_wall < max(to, 0.5)
        if not fresh:
            self._thawed_at = wall
        self._last_step_wall = wall
        live = wall - self._thawed_at > SELF_FREEZE_S
        req, opt = self.inputs.lost(now, state, to, self.cfg.map_tf_timeout_s, stale_checks=fresh,
                                    liveliness_checks=live)
        if state is None and self._tf_bad_since is not None and now - self._tf_bad_since > to:
            f = self.cfg.frames
            req.setdefault("TF", f"no TF {f.map}→{f.odom}→{f.base} for {now - self._tf_bad_since:.1f} s")
        return req, opt

    def _apply_inputs(self, rec: GoalRecord | None, now: float, state: RobotState | None) -> bool:
        """Pause / resume / fail the live run by its inputs; True when this tick must not drive. Lock held."""
        req, opt = self._inputs_lost(now, state)
        verdict = self.grace.update(now, time.monotonic(), req)
        degraded = "; ".join(f"{k}: {v}" for k, v in sorted(opt.items()))
        if degraded != self._degraded:
            self._degraded = degraded
            if degraded:
                log.warning("degraded (optional input lost, going on): %s", degraded)
        if rec is None or rec.state in TERMINAL:
            if verdict.resumed:
                self.nav.resume()
            return False
        if verdict.state == GRACE_FAILED:
            self.nav.resume()
            self._end_active(verdict.detail, canceled=False)
            return True
        if verdict.state == GRACE_PAUSED:
            if not self.nav.paused:
                log.warning("run %s paused: %s", rec.run_id, verdict.detail)
            self.nav.pause(verdict.detail)
            if self._moving or not self._paused_zero_sent:
                self.publish_zero()
                self._paused_zero_sent = True
            return True
        self._paused_zero_sent = False
        if verdict.resumed:
            log.info("run %s resumed: inputs are back", rec.run_id)
            self.nav.resume()
        return False

    def _step(self, now: float) -> None:
        try:
            state: RobotState | None = self.inputs.robot_state(now)
            self._tf_bad_since = None
        except TfError:
            state = None
            self._tf_bad_since = now if self._tf_bad_since is None else self._tf_bad_since
        grid, self._grid_seq = self.inputs.latest_grid(self._grid_seq)
        scan_msg, self._scan_seq = self.inputs.latest_scan(self._scan_seq)
        with self.lock:
            rec = self.nav.active
            live = rec is not None and rec.state not in TERMINAL
            hold = self._apply_inputs(rec, now, state)
            if live:
                if hold or rec.state in TERMINAL:
                    return
                if self._paused:
                    return
                if state is None and self._moving:  # pose unknown for now: do not drive blind
                    self.publish_zero()
            if state is None or not (live or grid is not None or scan_msg is not None):
                return  # idle and nothing new: skip the tick
            self._state = state
            self.apply_speed()
            scan = self.inputs.core_scan(scan_msg, state.pose) if scan_msg is not None else None
            expected = self.latency.expected(state.tf_age)
            self.nav.controller.set_latency(expected, self._sent)
            cmd = self.nav.tick(now, state.pose, state.vel, grid, scan[0] if scan else None,
                                scan[1] if scan else None)
            if live:
                if self._degraded and rec.state == RUNNING:
                    rec.detail = f"{rec.detail}; degraded: {self._degraded}"
                self._publish_cmd(rec, cmd.vx, cmd.vy, cmd.wz)
                self._note_latency(now, state.tf_age, expected)
                if rec.state in TERMINAL:
                    self.speed.run_ended(rec.run_id)
            self._publish_plan(now)
            self._sync_journal()

    def _note_latency(self, now: float, pose_age: float, expected: float) -> None:
        """After a driving tick's command went out: its duration in clock time feeds the latency estimate
        (a tick at rtf 3 costs three times its wall time in sim time); a summary line now and then."""
        self.latency.add_tick(self.inputs.clock.now() - now)
        self._latency_seen.append((pose_age, expected))
        if now - self._latency_logged < LATENCY_LOG_S:
            return
        if self._latency_seen and math.isfinite(self._latency_logged):
            ages = sorted(a for a, _ in self._latency_seen)
            exp = sorted(e for _, e in self._latency_seen)
            log.info("control latency over %d ticks: pose age median %.0f ms, p90 %.0f ms; estimated latency median "
                     "%.0f ms, p90 %.0f ms, max %.0f ms (clock time)", len(ages), 1e3 * ages[len(ages) // 2],
                     1e3 * ages[int(0.9 * len(ages))], 1e3 * exp[len(exp) // 2], 1e3 * exp[int(0.9 * len(exp))],
                     1e3 * exp[-1])
        self._latency_seen.clear()
        self._latency_logged = now

    def _publish_cmd(self, rec: GoalRecord, vx: float, vy: float, wz: float) -> None:
        if rec.state in (PENDING, RUNNING) or self._moving:
            self.pubs.cmd_vel.publish(twist(vx, vy, wz))
            self._moving = bool(vx or vy or wz)
            self._sent = (vx, vy, wz)

    def _publish_plan(self, now: float) -> None:
        path = self.nav.path
        if self.pubs.plan is None or len(path) == 0 or path is self._plan_sent:
            return
        self._plan_sent = path
        d = np.diff(path, axis=0)
        yaw = np.append(np.arctan2(d[:, 1], d[:, 0]), 0.0) if len(path) > 1 else np.zeros(1)
        if len(path) > 1:
            yaw[-1] = yaw[-2]
        mf = self.cfg.frames.map
        self.pubs.plan.publish(Path(header=header(now, mf),
                                    poses=[pose_stamped(float(x), float(y), float(a), now, mf)
                                           for (x, y), a in zip(path, yaw, strict=True)]))
