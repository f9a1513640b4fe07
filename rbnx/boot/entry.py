"""One package instance's lifecycle as a non-blocking state machine: spawn → registered → INIT →
(deferred → retry …) → ACTIVATE → active; and its shutdown.

Non-blocking steps let the orchestrator keep retrying parked (`Deferred`) entries while it starts the
next ones, which is what makes list order irrelevant for dependencies.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import grpc

from rbnx.atlas_rpc import CMD, Atlas, AtlasError, Driver, DriverReply, driver_capability
from rbnx.boot.backoff import Backoff
from rbnx.boot.procs import ProcGroup, proc_start_ticks, run_hook, spawn, tail
from rbnx.boot.statefile import run_dir
from rbnx.boot.supervise import RestartTracker
from rbnx.models import ResolvedEntry


def numba_cache_dir(env: dict[str, str]) -> Path:
    """$XDG_CACHE_HOME/robonix-nav/numba (default ~/.cache/...): writable and kept between boots."""
    base = env.get("XDG_CACHE_HOME") or os.path.join(env.get("HOME") or os.path.expanduser("~"), ".cache")
    return Path(base) / "robonix-nav" / "numba"


REGISTER_TIMEOUT_S = 60.0
STOP_HOOK_TIMEOUT_S = 20.0
DRIVER_SHUTDOWN_TIMEOUT_S = 5.0
QUERY_PERIOD_S = 0.1


def driver_timeout() -> float:
    """ROBONIX_DRIVER_INIT_TIMEOUT_S bounds INIT and ACTIVATE (robonix default 90 s)."""
    try:
        return float(os.environ.get("ROBONIX_DRIVER_INIT_TIMEOUT_S", "90"))
    except ValueError:
        return 90.0


@dataclass
class Timing:
    register_timeout: float = REGISTER_TIMEOUT_S
    driver_timeout: float = field(default_factory=driver_timeout)
    # A Deferred retry is one cheap RPC; a short cap keeps a parked entry within 0.25 s of its input
    # appearing (that input's registration is not always a state change rbnx can see and react to).
    backoff_initial: float = 0.1
    backoff_max: float = 0.25


@dataclass
class EntryRunner:
    """Drives one entry; `state` is what the progress view shows."""

    entry: ResolvedEntry
    env: dict[str, str]
    log_path: Path
    timing: Timing
    state: str = "pending"
    detail: str = ""
    failure: str = ""
    log_tail: list[str] = field(default_factory=list)
    proc: ProcGroup | None = None
    driver: Driver | None = None
    started_at: float = 0.0
    ready_at: float = 0.0
    _phase: str = "pending"  # pending|registering|init|activate|deferred|done|failed
    _future: grpc.Future | None = None
    _cmd: int = 0
    _next_query: float = 0.0
    _next_retry: float = 0.0
    _backoff: Backoff = field(default_factory=Backoff)
    _retry_cmd: int = 0
    _atlas_addr: str = ""
    _stale_reg: str = ""
    #: CMD_INIT answered Err (not Deferred, not a timeout): the provider refused its config, which no retry
    #: or restart can change, so the boot stops (see Orchestrator.boot)
    refused: bool = False
    restart_tracker: RestartTracker = field(init=False)
    #: the activation state to drive a restarted process back to (what the atlas showed at its death)
    restart_target: str | None = None

    def __post_init__(self) -> None:
        self.restart_tracker = RestartTracker(self.entry.restart)

    @property
    def restarts(self) -> int:
        """How often the supervisor started this entry again (0 = first run)."""
        return self.restart_tracker.restarts

    @property
    def name(self) -> str:
        return self.entry.name

    @property
    def target(self) -> str:
        """Skills and `autostart: false` entries stop at INACTIVE: someone else decides when they run; a
        restarted process goes back to the state it had when it died."""
        if self.restart_target is not None:
            return self.restart_target
        return "inactive" if self.entry.kind == "skill" or not self.entry.autostart else "active"

    @property
    def settled(self) -> bool:
        """Reached its target or failed: nothing more to do during boot."""
        return self._phase in ("done", "failed")

    @property
    def parked(self) -> bool:
        return self._phase == "deferred"

    @property
    def ok(self) -> bool:
        return self._phase == "done"

    # ------------------------------------------------------------------ start

    def child_env(self, atlas_addr: str) -> dict[str, str]:
        env = dict(self.env)
        env.update(
            RBNX_INSTANCE_NAME=self.name,
            RBNX_DEPLOY_MANAGED="1",
            ROBONIX_ATLAS=atlas_addr,
            RBNX_PACKAGE_ROOT=str(self.entry.root),
            # pidfiles etc. of this deployment only: another deployment's stop hook never sees them
            RBNX_RUN_DIR=str(run_dir(env.get("RBNX_DEPLOY_NAME", ""), atlas_addr, env)),
            PYTHONUNBUFFERED="1",
        )
        if self.restarts:
            env["RBNX_RESTARTS"] = str(self.restarts)  # "you are a restart": resume saved work
        # numba compiles the planner kernels once into the user's cache, not next to installed sources
        # (often read-only) where every boot would compile them again.
        env.setdefault("NUMBA_CACHE_DIR", str(numba_cache_dir(env)))
        # Packages started by this rbnx use its environment's `python` unless PATH already has it.
        bindir = os.path.dirname(sys.executable)
        if bindir not in env.get("PATH", "").split(os.pathsep):
            env["PATH"] = os.pathsep.join(p for p in (bindir, env.get("PATH", "")) if p)
        return env

    def start(self, atlas_addr: str, atlas: Atlas | None = None, append_log: bool = False) -> None:
        """Spawn the package; a record already in the atlas under this name is stale and is not waited on."""
        if atlas is not None:
            try:
                old = atlas.provider(self.name)
                self._stale_reg = getattr(old, "registration_id", "") if old is not None else ""
            except AtlasError:
                pass
        self._backoff = Backoff(self.timing.backoff_initial, 2.0, self.timing.backoff_max)
        self.started_at = time.monotonic()
        self._atlas_addr = atlas_addr
        self._set("starting")
        try:
            self.proc = spawn(self.name, ["bash", "-c", self.entry.manifest.start], self.entry.root,
                              self.child_env(atlas_addr), self.log_path, append=append_log)
        except OSError as exc:
            self._fail(f"cannot start: {exc}")
            return
        self._phase = "registering"

    def respawn(self, atlas: Atlas) -> None:
        """Start the package again after it died (the supervisor counted the restart first): same config,
        same target state; the atlas record of the dead process is stale and is not waited on."""
        if self.proc is not None and self.proc.alive_pids():
            self.proc.stop(2.0)
        if self.driver is not None:
            self.driver.close()
            self.driver = None
        self._future = None
        self.failure, self.log_tail = "", []
        self.start(self._atlas_addr, atlas, append_log=True)

    # ------------------------------------------------------------------ stepping

    def step(self, atlas: Atlas, now: float, deadline: float) -> None:
        """Advance without blocking (a Query at most); called repeatedly by the orchestrator."""
        if self._phase in ("pending", "done", "failed"):
            return
        if self.proc is not None and not self.proc.running():
            self._fail(f"process exited with code {self.proc.popen.returncode}", with_log=True)
            return
        if self._phase == "registering":
            self._step_register(atlas, now)
        elif self._phase in ("init", "activate"):
            self._step_driver(now, deadline)
        elif self._phase == "deferred":
            if now >= deadline:
                self._fail(f"still deferred at the boot deadline: {self.detail or 'no reason given'}")
            elif now >= self._next_retry:
                self._send(self._retry_cmd)

    def retry_now(self, now: float) -> None:
        """Another entry made progress: a parked entry may be unblocked, so retry it without backoff."""
        if self._phase == "deferred":
            self._next_retry = min(self._next_retry, now)

    def _step_register(self, atlas: Atlas, now: float) -> None:
        if now >= self.started_at + self.timing.register_timeout:
            self._fail(f"no provider registered as {self.name!r} within {self.timing.register_timeout:g}s",
                       with_log=True)
            return
        if now < self._next_query:
            return
        self._next_query = now + QUERY_PERIOD_S
        try:
            prov = atlas.provider(self.name)
        except AtlasError:
            return  # transient; the register deadline still applies
        if prov is None or prov.state == 5 or (self._stale_reg and prov.registration_id == self._stale_reg):
            return  # not (re)registered yet by the process we started
        self._set("registered")
        cid = driver_capability(prov)
        if cid is None:
            if prov.state == 3:  # a provider without a Driver goes straight to ACTIVE
                self._done("active")
            return
        try:
            endpoint, params = atlas.endpoint(self.name, cid, 1)
        except AtlasError:
            return
        self.driver = Driver(endpoint, params)
        self._send(CMD.CMD_INIT)

    def _send(self, cmd: int) -> None:
        assert self.driver is not None
        self._cmd = cmd
        self._phase = "init" if cmd == CMD.CMD_INIT else "activate"
        config = self.entry.config if cmd == CMD.CMD_INIT else None
        self._future = self.driver.call_async(cmd, config, self.timing.driver_timeout)

    def _step_driver(self, now: float, deadline: float) -> None:
        assert self._future is not None
        assert self.driver is not None
        if not self._future.done():
            return
        reply: DriverReply = self.driver.result(self._future)
        self._future = None
        what = "CMD_INIT" if self._cmd == CMD.CMD_INIT else "CMD_ACTIVATE"
        if reply.ok:
            self._backoff.reset()
            if self._cmd == CMD.CMD_INIT and self.target == "active":
                self._set("inactive")
                self._send(CMD.CMD_ACTIVATE)
            else:
                self._done("inactive" if self._cmd == CMD.CMD_INIT else "active")
        elif reply.state == "deferred":
            reason = reply.error or "deferred"
            if now >= deadline:
                self._fail(f"still deferred at the boot deadline: {reason}")
                return
            self._phase = "deferred"
            self._retry_cmd = self._cmd
            self._next_retry = now + self._backoff.next_delay()
            self._set("deferred", reason)
        elif "deadline_exceeded" in reply.error:
            self._fail(f"{what} timed out after {self.timing.driver_timeout:g}s", with_log=True)
        else:
            self.refused = self._cmd == CMD.CMD_INIT
            self._fail(f"{what}: {reply.error or reply.state or 'failed'}", with_log=True)

    # ------------------------------------------------------------------ outcomes

    def _set(self, state: str, detail: str = "") -> None:
        self.state, self.detail = state, detail

    def _done(self, state: str) -> None:
        self._phase = "done"
        self.ready_at = time.monotonic()
        self._set(state)
        if self.proc:
            self.proc.remember_descendants()

    def _fail(self, reason: str, with_log: bool = False, term_timeout: float = 5.0) -> None:
        """Record the failure and kill this package's group right away (the boot carries on)."""
        self._phase = "failed"
        self.failure = reason
        self._set("failed", reason)
        if with_log:
            self.log_tail = tail(self.log_path)
        if self._future is not None:
            self._future.cancel()
            self._future = None
        if self.proc is not None:
            self.proc.stop(term_timeout)

    def abort(self) -> None:
        """Boot interrupted: cancel an in-flight Driver call."""
        if self._future is not None:
            self._future.cancel()
            self._future = None

    # ------------------------------------------------------------------ shutdown

    def shutdown(self, term_timeout: float) -> str:
        """CMD_SHUTDOWN → `stop:` hook → SIGTERM the group → SIGKILL; returns a short outcome."""
        self.abort()
        if self.proc is None:
            return "not started"
        self.proc.remember_descendants()
        notes = []
        if self.driver is not None and self.proc.running():
            reply = self.driver.call(CMD.CMD_SHUTDOWN, None, DRIVER_SHUTDOWN_TIMEOUT_S)
            notes.append("CMD_SHUTDOWN ok" if reply.ok else f"CMD_SHUTDOWN: {reply.error or reply.state}")
            self.proc.wait_gone(min(3.0, term_timeout))
        stop = self.entry.manifest.stop
        if stop and stop.strip():
            ok, how = run_hook(f"{self.name}-stop", stop, self.entry.root, self.child_env(self._atlas_addr),
                              self.log_path, STOP_HOOK_TIMEOUT_S)
            notes.append("stop hook ok" if ok else f"stop hook {how}")
        ended = self.proc.stop(term_timeout)
        notes.append(ended)
        if self.driver is not None:
            self.driver.close()
        return ", ".join(notes)

    def describe(self) -> dict[str, Any]:
        """For the state file."""
        p = self.proc
        return {"name": self.name, "kind": self.entry.kind, "state": self.state, "root": str(self.entry.root),
                "run_dir": self.child_env(self._atlas_addr)["RBNX_RUN_DIR"] if self._atlas_addr else "",
                "manifest": str(self.entry.manifest_path),
                "pid": p.pid if p else None, "pgid": p.pgid if p else None,
                "start_ticks": p.start_ticks if p else None,
                "extra_pids": [[x, proc_start_ticks(x)] for x in sorted(p.extra_pids)] if p else [],
                "log": str(self.log_path), "ready_at": self.ready_at, "restarts": self.restarts}
