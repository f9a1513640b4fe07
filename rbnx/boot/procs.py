"""Process groups for packages and the atlas: spawn, inspect via /proc, stop by PID/PGID only.

Every package runs in its own session (= its own process group), so one killpg reaches the whole
package and nothing else; /proc is read directly (no psutil) to see what is still alive.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from robonix_api.procs import (  # noqa: F401  (re-exported: rbnx's modules and tests read /proc through here)
    descendants,
    group_members,
    pid_alive,
    proc_start_ticks,
    proc_state,
    stop_ladder,
    wait_gone,
)


def tail(path: Path, n: int = 15) -> list[str]:
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError:
        return []
    return lines[-n:]


@dataclass
class ProcGroup:
    """A spawned shell command in its own session; pgid == pid of the leader."""

    name: str
    popen: subprocess.Popen[bytes]
    log_path: Path | None
    start_ticks: int | None
    extra_pids: set[int]
    log_offset: int = 0  # size of the log before this run (appended logs of restarted processes)

    @property
    def pid(self) -> int:
        return self.popen.pid

    @property
    def pgid(self) -> int:
        return self.popen.pid

    def running(self) -> bool:
        """Leader still running (reaps it if it exited)."""
        return self.popen.poll() is None

    def remember_descendants(self) -> None:
        """Note children that may escape the group (setsid) so stop() can reach them too."""
        if self.running():
            self.extra_pids.update(descendants(self.pid))

    def alive_pids(self) -> list[int]:
        self.popen.poll()
        pids = set(group_members(self.pgid)) | {p for p in self.extra_pids if pid_alive(p)}
        if self.popen.returncode is None:
            pids.add(self.pid)
        return sorted(pids)

    def signal(self, sig: int) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pgid, sig)
        for p in list(self.extra_pids):
            if pid_alive(p):
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.kill(p, sig)

    def wait_gone(self, timeout: float) -> bool:
        """True once no process of the group (or an escaped descendant) is left, False after ``timeout``."""
        return wait_gone(lambda: bool(self.alive_pids()), timeout)

    def stop(self, term_timeout: float = 30.0) -> str:
        """SIGTERM the group, wait, then SIGKILL; returns how it ended ('exited'|'terminated'|'killed')."""
        self.remember_descendants()
        return stop_ladder(self.signal, lambda: bool(self.alive_pids()), term_timeout)


_supervised = False


def set_supervised(on: bool) -> None:
    """While rbnx stays up as the supervisor, its children get SIGTERM if rbnx dies, even by SIGKILL, so a
    killed boot leaves nothing behind. Off for ``--exit-after-boot``, where children must outlive rbnx."""
    global _supervised
    _supervised = on


_SETPRIV = shutil.which("setpriv")
# Where setpriv is missing: a tiny interpreter (no site import) sets the parent-death signal on itself and
# execs the command; it is started by vfork+exec like any other child, so no fork() happens either.
_PDEATHSIG_SHIM = ("import ctypes, os, sys; ctypes.CDLL(None).prctl(1, int(sys.argv[1])); "
                   "os.execvp(sys.argv[2], sys.argv[2:])")


def with_parent_death_signal(command: list[str], sig: signal.Signals = signal.SIGTERM) -> list[str]:
    """The command wrapped so that the child gets ``sig`` when its parent (rbnx) dies.

    Why not ``preexec_fn``: any preexec_fn makes Python use fork() instead of vfork(), and fork() runs
    gRPC's atfork handlers in the child (unless fork support is off), whose pollers then trip over the
    descriptors the child closes before exec: under load the child aborts (SIGSEGV/SIGABRT, "epoll_wait
    error: Bad file descriptor" in the entry's log) or hangs before it ever runs. rbnx holds gRPC channels
    while it spawns, so the parent-death signal is set after a vfork-exec instead: by util-linux
    ``setpriv``, else by a one-line Python shim that execs the command.
    """
    if _SETPRIV:
        return [_SETPRIV, "--pdeathsig", sig.name.removeprefix("SIG"), "--", *command]
    return [sys.executable, "-S", "-c", _PDEATHSIG_SHIM, str(int(sig)), *command]


def spawn(name: str, command: list[str], cwd: Path, env: Mapping[str, str], log_path: Path | None,
          append: bool = False) -> ProcGroup:
    """Start `command` in a new session with stdout+stderr to `log_path` (or inherited when None)."""
    if _supervised:
        command = with_parent_death_signal(command)
    out = open(log_path, "ab" if append else "wb") if log_path else None  # noqa: SIM115
    try:
        popen = subprocess.Popen(
            command, cwd=str(cwd), env=dict(env), stdin=subprocess.DEVNULL,
            stdout=out, stderr=subprocess.STDOUT if out else None, start_new_session=True,
        )
    finally:
        if out:
            out.close()
    return ProcGroup(name, popen, log_path, proc_start_ticks(popen.pid), set())


def run_hook(name: str, script: str, cwd: Path, env: Mapping[str, str], log_path: Path | None,
             timeout: float) -> tuple[bool, str]:
    """Run a build/stop hook with `bash -c` in its own group; kill the group when it overruns."""
    group = spawn(name, ["bash", "-c", script], cwd, env, log_path, append=True)
    try:
        rc = group.popen.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        group.stop(term_timeout=2.0)
        return False, f"timed out after {timeout:g}s"
    finally:
        if group.alive_pids():
            group.stop(term_timeout=2.0)
    return rc == 0, f"exit code {rc}"


def stop_recorded(pid: int | None, pgid: int | None, start_ticks: int | None,
                  extra: list[tuple[int, int | None]], term_timeout: float) -> str:
    """Stop a group this rbnx did not spawn itself (from a state file): same TERM → KILL ladder.

    Safe against PID reuse: the leader is signalled only if its start time matches, and a PGID cannot be
    handed out again while any member of the group still lives.
    """

    extra_pids = [p for p, t in extra if pid_alive(p, t)]

    def alive() -> list[int]:
        pids = set(group_members(pgid)) if pgid else set()
        if pid and pid_alive(pid, start_ticks):
            pids.add(pid)
        return sorted(pids | {p for p in extra_pids if pid_alive(p)})

    def send(sig: int) -> None:
        if pgid and group_members(pgid):
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(pgid, sig)
        for p in [*extra_pids, *([pid] if pid and pid_alive(pid, start_ticks) else [])]:
            if pid_alive(p):
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.kill(p, sig)

    return stop_ladder(send, lambda: bool(alive()), term_timeout)
