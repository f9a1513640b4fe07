"""The running work of the HAL: one thread steps physics in chunks, paces to ``real_time_factor`` and
publishes on sim time. A :class:`SimLoop` is the work of one session (see ``robonix_api.hosting``).

One thread owns the (not thread-safe) simulator; RPC handlers and the /cmd_vel callback reach it
through ``call()``, which takes the same lock the loop holds while stepping one chunk (<= one clock
period of sim time), so they never wait long.

Modes: ``ACTIVE`` steps and publishes at the configured sim-time rates. ``held`` (before the first
ACTIVATE and after DEACTIVATE) freezes sim time and republishes the current state (/clock, /odom,
TF, /scan, ground truth) at ``hold_rate_hz`` of wall time, so consumers can still resolve frames. On
DEACTIVATE the base is first braked to rest (<= 2 s of sim time, still paced) and /cmd_vel is ignored.

Command lag bound: while the base is executing a non-zero /cmd_vel, the loop does not run more than
``command_lag_bound_s`` of sim time past that command's arrival; it waits (wall time, at most
``COMMAND_WAIT_MAX_S`` per command) for the next one. Why: at a real-time factor of 3 every wall millisecond a
controller tick takes becomes three of sim time, so a tick slowed by a loaded machine (or a long replan) lets
the base drive blind for far longer than the same controller would on the robot at real time. Measured in a
``rbnx demo`` on a loaded machine: control ticks of ~1 s of sim time on the first goal, and the contact at a
door jamb that followed. A real base cannot wait; a simulator can, and should, so that what is measured is
navigation rather than the machine's load. A controller that stops sending (crashed, paused) costs at most
``COMMAND_WAIT_MAX_S`` of wall time before the loop runs on and the command's own timeout stops the base.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

from hal_panda_mobile.outputs import Outputs, Snapshot
from hal_panda_mobile.persist import SimContinuity
from hal_panda_mobile.sim import PandaMobileSim

log = logging.getLogger("hal_panda_mobile.loop")
T = TypeVar("T")

HELD, ACTIVE, BRAKING, STOPPED = "held", "active", "braking", "stopped"
BRAKE_MAX_S = 2.0  # sim seconds allowed to come to rest on DEACTIVATE
REST_SPEED = 1e-3  # m/s and rad/s
LAG_RESET_S = 0.5  # wall seconds behind schedule before the pacing anchor is reset (no catch-up burst)
COMMAND_WAIT_MAX_S = 0.4  # wall s the loop waits for a follow-up command (under navigation's 0.5 s /clock stall check)
COMMAND_WAIT_SLICE_S = 0.02  # wall seconds between checks of the mode while waiting for a command
WAIT_WARN_EVERY_S = 10.0  # wall seconds between warnings that a wait for a command gave up


@dataclass(frozen=True)
class LoopRates:
    """Sim-time rates (Hz); ``None`` disables that output."""

    odom: float
    scan: float
    clock: float | None
    ground_truth: float | None
    hold: float = 1.0


@dataclass
class LoopStats:
    chunks: int = 0
    errors: int = 0
    last_error: str = ""
    lag_resets: int = 0
    active_wall_s: float = 0.0
    active_sim_s: float = 0.0
    cmd_ignored: int = 0
    cmd_waits: int = 0  # times the loop waited for a command newer than command_lag_bound_s of sim time
    cmd_wait_wall_s: float = 0.0
    cmd_wait_timeouts: int = 0  # waits that ended after COMMAND_WAIT_MAX_S without a new command
    cmd_wait_lag_max_s: float = 0.0  # largest sim-time age of the command at which a wait began
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def achieved_rtf(self) -> float:
        return self.active_sim_s / self.active_wall_s if self.active_wall_s > 0 else 0.0

    def as_dict(self) -> dict[str, Any]:
        return {"chunks": self.chunks, "errors": self.errors, "last_error": self.last_error,
                "lag_resets": self.lag_resets, "active_wall_s": round(self.active_wall_s, 3),
                "active_sim_s": round(self.active_sim_s, 3), "achieved_rtf": round(self.achieved_rtf, 3),
                "cmd_ignored": self.cmd_ignored, "cmd_waits": self.cmd_waits,
                "cmd_wait_wall_s": round(self.cmd_wait_wall_s, 3), "cmd_wait_timeouts": self.cmd_wait_timeouts,
                "cmd_wait_lag_max_s": round(self.cmd_wait_lag_max_s, 3),
                **self.extra}


class SimLoop:
    """Owns the simulator and its outputs for one session; ``close()`` stops the thread and the writers."""

    def __init__(self, sim: PandaMobileSim, outputs: Outputs, rates: LoopRates, *, real_time_factor: float,
                 use_sim_time: bool = True, command_lag_bound_s: float = 0.0,
                 command_wait_max_s: float = COMMAND_WAIT_MAX_S, continuity: SimContinuity | None = None) -> None:
        self.sim, self.outputs, self.rates = sim, outputs, rates
        self.continuity = continuity  # saves the state a crash-restarted HAL resumes (hal_panda_mobile.persist)
        self.rtf = real_time_factor
        self.command_lag_bound_s = command_lag_bound_s
        self.command_wait_max_s = command_wait_max_s
        self._cmd_at = -math.inf  # sim time the last non-zero command arrived (-inf: none is being executed)
        self._cmd_seq = 0  # counts accepted commands, so a wait knows whether a new one came
        self._waited_seq = -1  # the command whose wait already timed out (it is not waited for again)
        self._cmd_arrived = threading.Event()
        self._wait_warned_until = 0.0  # monotonic time before which a wait that gives up is not logged again
        self.use_sim_time = use_sim_time
        self.stats = LoopStats()
        self.cleared_at = -1.0  # collisions at or before this sim time were hidden by a reset
        self.spawn_count = 0  # boxes spawned so far (names the next unnamed one)
        self._lock = threading.RLock()
        self._wake = threading.Event()
        self._mode = HELD
        self._republish = True  # publish the initial state at once
        self._brake_until = 0.0
        t = sim.time
        self._due = {"odom": t, "scan": t, "clock": t, "ground_truth": t}
        self._periods = {"odom": 1.0 / rates.odom, "scan": 1.0 / rates.scan,
                         "clock": 1.0 / rates.clock if rates.clock else math.inf,
                         "ground_truth": 1.0 / rates.ground_truth if rates.ground_truth else math.inf}
        self._thread = threading.Thread(target=self._run, name="hal-sim-loop", daemon=True)

    # ------------------------------------------------------------------ control (any thread)
    @property
    def mode(self) -> str:
        return self._mode

    def start(self) -> None:
        self._thread.start()

    def activate(self) -> None:
        with self._lock:
            self._mode = ACTIVE
        self._wake.set()

    def deactivate(self) -> None:
        """Zero the command, brake to rest (paced), then hold with sim time frozen."""
        with self._lock:
            self.sim.stop()
            self._brake_until = self.sim.time + BRAKE_MAX_S
            self._mode = BRAKING
        self._wake.set()

    def stop(self, timeout_s: float = 10.0) -> None:
        with self._lock:
            self._mode = STOPPED
        self._wake.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)

    def close(self, reason: str = "") -> None:
        """End of the session: stop the loop, then release the DDS writers."""
        self.stop()
        if self.continuity is not None:
            self.continuity.discard()  # ended on purpose: a later start is a new run
        st = self.stats
        if st.cmd_waits:
            log.info("waited for /cmd_vel %d times (%.1f s of wall time, %d gave up; command lag bound %.2f s of sim "
                     "time); achieved real-time factor %.2f", st.cmd_waits, st.cmd_wait_wall_s, st.cmd_wait_timeouts,
                     self.command_lag_bound_s, st.achieved_rtf)
        self.outputs.close()

    def call(self, fn: Callable[[PandaMobileSim], T], *, republish: bool = False) -> T:
        """Run ``fn(sim)`` under the sim lock; ``republish`` pushes the new state out at once."""
        with self._lock:
            result = fn(self.sim)
            if republish:
                self._republish = True
        if republish:
            self._wake.set()
        return result

    def cmd_vel(self, vx: float, vy: float, wz: float, vz: float = 0.0, wx: float = 0.0, wy: float = 0.0) -> bool:
        """Body twist stamped with the current sim time; ignored (False) unless ACTIVE."""
        with self._lock:
            if self._mode != ACTIVE:
                self.stats.cmd_ignored += 1
                return False
            status = self.sim.set_cmd_vel(vx, vy, wz, self.sim.time, vz=vz, wx=wx, wy=wy)
            moving = not status.rejected and (status.vx != 0.0 or status.vy != 0.0 or status.wz != 0.0)
            self._cmd_at = self.sim.time if moving else -math.inf
            self._cmd_seq += 1
        self._cmd_arrived.set()
        return True

    # ------------------------------------------------------------------ loop (own thread)
    def _stamp(self, t: float) -> float:
        return t if self.use_sim_time else time.time()

    def _run(self) -> None:
        anchor_wall, anchor_sim = time.monotonic(), self.sim.time
        was_stepping = False
        while self._mode != STOPPED:
            try:
                stepping = self._mode in (ACTIVE, BRAKING)
                if not stepping:
                    was_stepping = False
                    self._hold_once()
                    continue
                if not was_stepping:  # (re)start pacing from here
                    anchor_wall, anchor_sim = time.monotonic(), self.sim.time
                    was_stepping = True
                if self._command_stale():
                    self._wait_for_command()
                    anchor_wall, anchor_sim = time.monotonic(), self.sim.time  # the wait is not lag to catch up
                    continue
                t0 = time.monotonic()
                sim0 = self.sim.time
                self._step_chunk()
                self.stats.active_sim_s += self.sim.time - sim0
                if self.rtf > 0:
                    target = anchor_wall + (self.sim.time - anchor_sim) / self.rtf
                    delay = target - time.monotonic()
                    if delay > 0:
                        self._wake.wait(delay)
                        self._wake.clear()
                    elif -delay > LAG_RESET_S:
                        self.stats.lag_resets += 1
                        anchor_wall, anchor_sim = time.monotonic(), self.sim.time
                self.stats.active_wall_s += time.monotonic() - t0
            except Exception as exc:  # keep the sim alive; the error is counted and logged
                self.stats.errors += 1
                self.stats.last_error = f"{type(exc).__name__}: {exc}"
                log.exception("sim loop iteration failed (%d so far)", self.stats.errors)
                time.sleep(0.05)

    def _command_stale(self) -> bool:
        """True while the base executes a non-zero command older than the lag bound (and not already waited on)."""
        with self._lock:
            return (self.command_lag_bound_s > 0.0 and self._mode == ACTIVE and self._waited_seq != self._cmd_seq
                    and self.sim.commanding and self.sim.time - self._cmd_at >= self.command_lag_bound_s)

    def _wait_for_command(self) -> None:
        """Block stepping until a newer command arrives, the mode changes, or ``command_wait_max_s`` passes."""
        with self._lock:
            seq = self._cmd_seq
            self._cmd_arrived.clear()
            lag = self.sim.time - self._cmd_at
        t0 = time.monotonic()
        self.stats.cmd_waits += 1
        self.stats.cmd_wait_lag_max_s = max(self.stats.cmd_wait_lag_max_s, lag)
        while True:
            self._cmd_arrived.wait(COMMAND_WAIT_SLICE_S)
            self._cmd_arrived.clear()
            with self._lock:
                if self._cmd_seq != seq or self._mode != ACTIVE:
                    break
            if time.monotonic() - t0 >= self.command_wait_max_s:
                with self._lock:
                    self._waited_seq = seq
                self.stats.cmd_wait_timeouts += 1
                if time.monotonic() >= self._wait_warned_until:   # a slow publisher would warn on every command
                    self._wait_warned_until = time.monotonic() + WAIT_WARN_EVERY_S
                    log.warning("no new /cmd_vel for %.1f s of wall time (last one %.2f s of sim time ago); running on "
                                "without waiting for it (%d time(s) so far)", self.command_wait_max_s,
                                self.sim.time - self._cmd_at, self.stats.cmd_wait_timeouts)
                break
        waited = time.monotonic() - t0
        self.stats.cmd_wait_wall_s += waited
        self.stats.active_wall_s += waited  # the achieved real-time factor counts the waits

    def _hold_once(self) -> None:
        with self._lock:
            due = self._republish
            self._republish = False
            snap = self._snapshot(everything=True) if due else None
        if snap is not None:
            self.outputs.publish(snap)
            return
        if self._wake.wait(1.0 / self.rates.hold):
            self._wake.clear()
            return
        with self._lock:
            if self._mode == HELD:
                self._republish = True

    def _step_chunk(self) -> None:
        with self._lock:
            sim = self.sim
            nxt = min(self._due.values())
            n = max(1, math.ceil((nxt - sim.time) / sim.timestep - 1e-9))
            sim.step(n)
            self.stats.chunks += 1
            snap = self._snapshot(everything=self._republish)
            self._republish = False
            if self._mode == BRAKING:
                gt = sim.ground_truth()
                if max(abs(v) for v in gt[3:]) < REST_SPEED or sim.time >= self._brake_until:
                    self._mode = HELD
                    log.info("braked to rest at sim t=%.3f; holding", sim.time)
            saved = self.continuity.maybe_save(sim, sim.time) if self.continuity is not None else None
        if snap is not None:
            self.outputs.publish(snap)
        if saved is not None:
            self.continuity.write(saved)  # type: ignore[union-attr]

    def _snapshot(self, everything: bool) -> Snapshot | None:
        """Read the outputs that are due (all of them with ``everything``) and advance their schedule."""
        sim, t = self.sim, self.sim.time
        due = {k for k, when in self._due.items() if everything or t >= when - 1e-9}
        if not due:
            return None
        for k in due:
            p = self._periods[k]
            if math.isfinite(p):
                nxt = self._due[k]
                while nxt <= t + 1e-9:
                    nxt += p
                self._due[k] = nxt
            else:
                self._due[k] = math.inf
        want = {k for k in due if math.isfinite(self._periods[k])}
        return Snapshot(t=t, stamp=self._stamp(t),
                        odom=sim.odometry() if "odom" in want else None,
                        ground_truth=sim.ground_truth() if "ground_truth" in want else None,
                        scan=sim.scan() if "scan" in want else None,
                        clock="clock" in want)
