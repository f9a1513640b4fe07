"""`rbnx demo`'s handle on `rbnx boot`, run as a child process.

The boot process owns every package process and tears them down in order on SIGINT, so the demo never
stops packages itself: it forwards SIGINT and waits. Only if the boot itself hangs or dies does the demo
fall back to stopping the processes the boot recorded in its state file (by PID + start time).
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from rbnx.atlas_rpc import STATE_NAMES, Atlas, AtlasError
from rbnx.boot.procs import pid_alive, stop_recorded, tail, with_parent_death_signal
from rbnx.boot.statefile import read_state
from robonix_api.auth import TOKEN_ENV


class DemoError(RuntimeError):
    """A failure the demo reports in a few lines and exits 1 for; ``lines`` are extra context (log tails)."""

    def __init__(self, message: str, lines: list[str] | None = None) -> None:
        super().__init__(message)
        self.lines = lines or []


def domain_free(domain: int) -> bool:
    """Heuristic: Cyclone's first participant of a domain binds UDP 7410 + 250*domain (default port mapping)."""
    port = 7410 + 250 * domain
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("127.0.0.1", port))
            return True
        except OSError:
            return False


def pick_domain_id(rng_seed: int | None = None) -> int:
    """A ROS_DOMAIN_ID nobody on this host seems to use, so the demo's DDS traffic stays its own."""
    import random

    rng = random.Random(rng_seed if rng_seed is not None else os.getpid() ^ time.time_ns())
    candidates = list(range(100, 230))
    rng.shuffle(candidates)
    return next((d for d in candidates if domain_free(d)), candidates[0])


class BootChild:
    """`rbnx boot -f DEPLOY --no-progress --log-dir OUT/logs` with its output in OUT/boot.log."""

    def __init__(self, deploy: Path, out: Path, env: dict[str, str], boot_timeout: float = 120.0) -> None:
        self.deploy = deploy
        self.out = out
        self.log_dir = out / "logs"
        self.boot_log = out / "boot.log"
        self.env = env
        self.boot_timeout = boot_timeout
        self.proc: subprocess.Popen[bytes] | None = None
        self.atlas: str | None = None
        self._lock = threading.Lock()

    @property
    def state_copy(self) -> Path:
        return self.log_dir / "rbnx-boot.json"

    def start(self) -> None:
        self.log_dir.mkdir(parents=True, exist_ok=True)
        cmd = [sys.executable, "-m", "rbnx.cli", "boot", "-f", str(self.deploy), "--no-progress",
               "--log-dir", str(self.log_dir), "--boot-timeout", f"{self.boot_timeout:g}", "--term-timeout", "20"]
        # SIGINT to the boot if the demo dies (even by SIGKILL), so the boot still cleans up; set after a
        # vfork-exec (no preexec_fn: that would fork() a process holding gRPC channels).
        cmd = with_parent_death_signal(cmd, signal.SIGINT)
        with open(self.boot_log, "wb") as fh:
            # Own session: a terminal's Ctrl-C reaches only the demo, which forwards exactly one SIGINT.
            self.proc = subprocess.Popen(cmd, env=self.env, stdout=fh, stderr=subprocess.STDOUT,
                                         stdin=subprocess.DEVNULL, start_new_session=True)

    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def state(self) -> dict[str, Any] | None:
        return read_state(self.state_copy)

    def log_tail(self, n: int = 12) -> list[str]:
        return tail(self.boot_log, n)

    # ------------------------------------------------------------------ readiness

    def wait_active(self, names: list[str], timeout: float, stop: threading.Event,
                    on_wait: Any = None) -> str:
        """Atlas address once every entry in ``names`` is ACTIVE; DemoError (with log tails) otherwise."""
        deadline = time.monotonic() + timeout
        states: dict[str, str] = {}
        while not stop.is_set():
            if not self.running():
                raise DemoError(f"rbnx boot exited with code {self.proc.returncode if self.proc else '?'} "
                                f"before the system was up (log {self.boot_log})", self.log_tail())
            st = self.state() or {}
            self.atlas = st.get("atlas") or self.atlas
            if st.get("token"):  # the deployment token: the demo's own calls (goals, map card) carry it
                os.environ[TOKEN_ENV] = str(st["token"])
            for child in st.get("children") or []:
                if child.get("state") == "failed":
                    log = Path(child.get("log") or "")
                    raise DemoError(f"{child['name']} failed to start (log {log})",
                                    tail(log, 15) if log.name else [])
            if self.atlas:
                states = self._atlas_states(names) or states
                if states and all(states.get(n) == "active" for n in names):
                    return self.atlas
                bad = [n for n in names if states.get(n) in ("error", "terminated")]
                if bad:
                    log = self.log_dir / f"{bad[0]}.log"
                    raise DemoError(f"{bad[0]} went to state {states[bad[0]].upper()} (log {log})", tail(log, 15))
            if on_wait is not None:
                on_wait(states)
            if time.monotonic() > deadline:
                waiting = [f"{n} ({states.get(n, 'not registered')})" for n in names if states.get(n) != "active"]
                first = next((n for n in names if states.get(n) != "active"), names[0])
                log = self.log_dir / f"{first}.log"
                raise DemoError(f"not ACTIVE after {timeout:g}s: {', '.join(waiting)} (log {log})", tail(log, 15))
            stop.wait(0.5)
        raise KeyboardInterrupt

    def _atlas_states(self, names: list[str]) -> dict[str, str]:
        try:
            with Atlas(self.atlas or "", timeout=2.0) as atlas:
                provs = atlas.query()
        except AtlasError:
            return {}
        return {p.id: STATE_NAMES.get(p.state, str(p.state)) for p in provs if p.id in names}

    # ------------------------------------------------------------------ shutdown

    def recorded(self) -> list[tuple[str, int, int | None]]:
        """(name, pid, start_ticks) of every process the boot recorded, itself included."""
        st = self.state() or {}
        out: list[tuple[str, int, int | None]] = []
        if st.get("pid"):
            out.append(("rbnx boot", int(st["pid"]), st.get("start_ticks")))
        if st.get("atlas_proc"):
            out.append(("atlas", int(st["atlas_proc"]["pid"]), st["atlas_proc"].get("start_ticks")))
        for c in st.get("children") or []:
            if c.get("pid"):
                out.append((c["name"], int(c["pid"]), c.get("start_ticks")))
            for pid, ticks in c.get("extra_pids") or []:
                out.append((c["name"], int(pid), ticks))
        return out

    def interrupt(self) -> None:
        """Forward one SIGINT (a second one makes boot hurry: short SIGTERM→SIGKILL grace)."""
        with self._lock:
            if self.running():
                assert self.proc is not None
                self.proc.send_signal(signal.SIGINT)

    def stop(self, timeout: float = 120.0) -> list[str]:
        """SIGINT the boot and wait for it; returns descriptions of recorded processes still alive after."""
        if self.proc is None:
            return []
        self.interrupt()
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.interrupt()
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self._reap_orphans()
        deadline = time.monotonic() + 10.0
        left = self._alive()
        while left and time.monotonic() < deadline:
            time.sleep(0.2)
            left = self._alive()
        return [f"{name} (pid {pid})" for name, pid, _ in left]

    def _alive(self) -> list[tuple[str, int, int | None]]:
        return [r for r in self.recorded() if pid_alive(r[1], r[2])]

    def _reap_orphans(self) -> None:
        """Only when the boot died without cleaning up: stop what it recorded, by PID (never by name)."""
        st = self.state() or {}
        procs = [*(st.get("children") or []), *([st["atlas_proc"]] if st.get("atlas_proc") else [])]
        for p in procs:
            if p.get("pid") and pid_alive(int(p["pid"]), p.get("start_ticks")):
                extra = [(int(x), t) for x, t in p.get("extra_pids") or []]
                stop_recorded(int(p["pid"]), p.get("pgid"), p.get("start_ticks"), extra, 5.0)
