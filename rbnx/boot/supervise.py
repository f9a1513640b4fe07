"""Supervision after boot: notice a process death at once, tell the atlas, restart by policy.

Why here and not in the atlas: the atlas only learns of a death when heartbeats lapse (tens of seconds),
while `rbnx boot` is the parent of every package and sees an exit within one poll. So on an exit it
pushes TERMINATED for that provider to the atlas (consumers looking it up stop using it now), then
restarts it per the entry's ``restart`` policy with exponential backoff and a cap on consecutive
restarts. A restarted package gets the same CMD_INIT config and is driven back to the activation state
it had when it died (ACTIVE stays ACTIVE, INACTIVE stays INACTIVE); ``RBNX_RESTARTS=<n>`` in its
environment tells it that it is a restart (the mapping service resumes its autosaved session then).

The policy arithmetic (:class:`RestartPolicy`, :class:`RestartTracker`) is pure and unit-tested; the
:class:`Supervisor` does the I/O (atlas RPCs, respawns) and runs in the boot's wait loop.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    from rbnx.atlas_rpc import Atlas
    from rbnx.boot.entry import EntryRunner
    from rbnx.boot.procs import ProcGroup

RestartMode = Literal["never", "on-failure", "always"]
RESTART_MODES: tuple[str, ...] = ("never", "on-failure", "always")
TERMINATED = 5  # robonix.atlas.LifecycleState.TERMINATED
ACTIVE = 3
INACTIVE = 2


@dataclass(frozen=True)
class RestartPolicy:
    """When and how often a process is started again after it exited on its own.

    ``max_restarts`` bounds *consecutive* restarts: a run that stayed up ``reset_after_s`` clears the
    count, so a package that crashes once a day is restarted every time, one that crashes at start is not
    restarted forever. Backoff doubles from ``backoff_s`` up to ``backoff_max_s``.
    """

    mode: RestartMode = "never"
    max_restarts: int = 5
    backoff_s: float = 0.5
    backoff_max_s: float = 10.0
    reset_after_s: float = 60.0

    def wants_restart(self, returncode: int | None) -> bool:
        """``on-failure``: a non-zero exit or a signal; ``always``: any exit; ``never``: none."""
        if self.mode == "always":
            return True
        if self.mode == "on-failure":
            return returncode != 0
        return False


@dataclass
class RestartTracker:
    """One process's restart bookkeeping (pure: the caller passes the clock)."""

    policy: RestartPolicy
    restarts: int = 0  # restarts done so far (shown in caps / progress / state file)
    streak: int = 0  # consecutive restarts without a run of reset_after_s
    due_at: float | None = None

    def on_exit(self, returncode: int | None, now: float, up_since: float) -> str:
        """Decide after an exit: 'restart' (``due_at`` set), 'give-up' (max reached) or 'stay-down'."""
        if not self.policy.wants_restart(returncode):
            return "stay-down"
        if now - up_since >= self.policy.reset_after_s:
            self.streak = 0
        if self.streak >= self.policy.max_restarts:
            return "give-up"
        delay = min(self.policy.backoff_max_s, self.policy.backoff_s * 2 ** self.streak)
        self.due_at = now + delay
        return "restart"

    def due(self, now: float) -> bool:
        return self.due_at is not None and now >= self.due_at

    def started(self) -> None:
        self.restarts += 1
        self.streak += 1
        self.due_at = None


def exit_text(returncode: int | None) -> str:
    if returncode is None:
        return "exited"
    if returncode < 0:
        return f"killed by signal {-returncode}"
    return f"exited with code {returncode}"


def mark_terminated(atlas: Atlas, name: str, detail: str) -> int | None:
    """Push TERMINATED for ``name``; returns the state it had before (None if the atlas does not know it)."""
    from rbnx.atlas_rpc import AtlasError
    from robonix_api.proto_gen import atlas_pb2

    try:
        resp = atlas._call("SetLifecycleState", atlas_pb2.SetLifecycleStateRequest(
            id=name, state=TERMINATED, detail=detail), timeout=2.0)
    except AtlasError:
        return None
    return int(resp.previous_state)


@dataclass
class _Watch:
    """What the supervisor knows about one entry between its death and its restart."""

    tracker: RestartTracker
    up_since: float = field(default_factory=time.monotonic)
    down: bool = False  # exited and not (yet) running again
    restarting: bool = False  # respawned, being driven to its target state


class Supervisor:
    """Runs in the boot's wait loop (``poll()`` every ~0.1 s) once the boot settled."""

    def __init__(self, runners: list[EntryRunner], atlas: Atlas, boot_timeout: float,
                 on_change: Callable[[], None], view: Any = None,
                 atlas_proc: ProcGroup | None = None, atlas_policy: RestartPolicy | None = None,
                 respawn_atlas: Callable[[], ProcGroup] | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        self.runners = runners
        self.atlas = atlas
        self.boot_timeout = boot_timeout
        self.on_change = on_change
        self.view = view
        self.atlas_proc = atlas_proc
        self.atlas_tracker = RestartTracker(atlas_policy or RestartPolicy())
        self.atlas_up_since = time.monotonic()
        self.atlas_down = False
        self.respawn_atlas = respawn_atlas
        self.log = log or (lambda msg: print(f"rbnx boot: {msg}", file=sys.stderr, flush=True))
        now = time.monotonic()
        self.watch = {r.name: _Watch(r.restart_tracker, up_since=now) for r in runners}

    # ------------------------------------------------------------------ entries

    def _show(self, r: EntryRunner, state: str, detail: str = "") -> None:
        r.state, r.detail = state, detail
        if self.view is not None:
            self.view.set(r.name, state, detail)
        self.on_change()

    def _on_death(self, r: EntryRunner, w: _Watch, now: float) -> None:
        assert r.proc is not None
        failed_start = w.restarting  # the restarted process failed to come up (stopped by its runner)
        rc = r.proc.popen.poll()
        how = f"failed to start again ({r.failure})" if failed_start else exit_text(rc)
        if failed_start and not rc:
            rc = 1  # a start that failed is a failure, however the stopped process exited
        prev = mark_terminated(self.atlas, r.name, f"process {how} (seen by rbnx boot)")
        if prev in (ACTIVE, INACTIVE) and not w.restarting:
            r.restart_target = "active" if prev == ACTIVE else "inactive"
        r.proc.stop(2.0)  # after telling the atlas: anything the dead leader left in its group goes too
        w.down, w.restarting = True, False
        decision = w.tracker.on_exit(rc, now, w.up_since)
        if decision == "restart":
            delay = (w.tracker.due_at or now) - now
            self.log(f"{r.name} {how}; marked TERMINATED on the atlas; restart "
                     f"{w.tracker.restarts + 1} in {delay:.1f}s (log {r.log_path})")
            self._show(r, "restarting", f"{how}; restart {w.tracker.restarts + 1} in {delay:.1f}s")
        else:
            why = (f"gave up after {w.tracker.streak} restarts" if decision == "give-up"
                   else f"restart: {w.tracker.policy.mode}")
            self.log(f"{r.name} {how}; marked TERMINATED on the atlas; not restarted ({why}; log {r.log_path})")
            self._show(r, "exited", f"{how}; {why}")

    def _poll_entry(self, r: EntryRunner, w: _Watch, now: float) -> None:
        if r.proc is None:
            return
        if w.restarting:
            r.step(self.atlas, now, r.started_at + self.boot_timeout)
            if r.ok:
                w.restarting = False
                w.up_since = now
                self.log(f"{r.name} restarted ({r.state}, restart {w.tracker.restarts}, "
                         f"{now - r.started_at:.2f}s)")
                self._show(r, r.state, f"restarts {w.tracker.restarts}")
            elif r.settled:  # failed while starting again: treat like a death
                self._on_death(r, w, now)
            elif self.view is not None:
                self.view.set(r.name, r.state, r.detail)
            return
        if w.down:
            if w.tracker.due(now):
                w.tracker.started()
                r.respawn(self.atlas)
                w.down, w.restarting, w.up_since = False, True, now
                self._show(r, r.state, f"restart {w.tracker.restarts}")
            return
        if r.ok and not r.proc.running():
            self._on_death(r, w, now)

    # ------------------------------------------------------------------ atlas

    def _poll_atlas(self, now: float) -> None:
        p = self.atlas_proc
        if p is None:
            return
        t = self.atlas_tracker
        if not self.atlas_down:
            if p.running():
                return
            rc = p.popen.returncode
            p.stop(2.0)
            self.atlas_down = True
            decision = t.on_exit(rc, now, self.atlas_up_since) if self.respawn_atlas else "stay-down"
            if decision == "restart":
                self.log(f"atlas {exit_text(rc)}; restart {t.restarts + 1} in {(t.due_at or now) - now:.1f}s "
                         "(providers re-register with it)")
            else:
                self.log(f"atlas {exit_text(rc)} (log {p.log_path}); not restarted "
                         f"(system.atlas.restart: {t.policy.mode})")
            self.on_change()
            return
        if t.due(now) and self.respawn_atlas is not None:
            t.started()
            try:
                self.atlas_proc = self.respawn_atlas()
            except Exception as exc:
                self.log(f"atlas restart {t.restarts} failed: {exc}")
                decision = t.on_exit(1, time.monotonic(), time.monotonic())
                if decision != "restart":
                    self.log("atlas: giving up")
                return
            self.atlas_down = False
            self.atlas_up_since = time.monotonic()
            self.log(f"atlas restarted (restart {t.restarts}, pid {self.atlas_proc.pid})")
            self.on_change()

    # ------------------------------------------------------------------ loop

    def poll(self) -> None:
        now = time.monotonic()
        self._poll_atlas(now)
        if self.atlas_down and self.atlas_tracker.due_at is not None:
            return  # a restart is pending: entries are looked at once the atlas is back
        for r in self.runners:
            self._poll_entry(r, self.watch[r.name], now)
        if self.view is not None:
            self.view.tick()
