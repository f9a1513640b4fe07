"""Child processes in their own process groups, and the one way to stop them: SIGTERM → wait → SIGKILL.

A provider that wraps other programs (a simulator, a bridge) must not leave them behind: teardown
signals every group with SIGTERM, waits, then SIGKILLs what is left, as robonix does. ``rbnx boot`` stops
its packages and the tests stop their children with the same ladder (:func:`stop_ladder`), and see what
is still alive through the /proc readers here (no psutil).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)

#: How long :func:`stop_ladder` waits after SIGKILL before it gives up on a process (it reports "killed").
KILL_WAIT_S = 10.0


def _stat_fields(pid: int) -> list[str] | None:
    """Fields of /proc/<pid>/stat after the command name (index 0 = state)."""
    try:
        data = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return data[data.rfind(")") + 2:].split()


def proc_state(pid: int) -> str | None:
    """The one-letter state of ``pid`` (R, S, T, Z …) or None when there is no such process."""
    f = _stat_fields(pid)
    return f[0] if f else None


def proc_start_ticks(pid: int) -> int | None:
    """Start time in clock ticks since boot; pairs with a PID to survive PID reuse."""
    f = _stat_fields(pid)
    return int(f[19]) if f else None


def pid_alive(pid: int, start_ticks: int | None = None) -> bool:
    """Running (not a zombie) and, when given, the same process as recorded."""
    f = _stat_fields(pid)
    if not f or f[0] in ("Z", "X"):
        return False
    return start_ticks is None or int(f[19]) == start_ticks


def _all_pids() -> list[int]:
    return [int(n) for n in os.listdir("/proc") if n.isdigit()]


def group_members(pgid: int) -> list[int]:
    """Live (non-zombie) processes whose process group is ``pgid``."""
    out = []
    for pid in _all_pids():
        f = _stat_fields(pid)
        if f and f[0] not in ("Z", "X") and int(f[2]) == pgid:
            out.append(pid)
    return out


def descendants(pid: int) -> list[int]:
    """Live descendants of ``pid`` (by parent links), including ones that left the group with setsid."""
    children: dict[int, list[int]] = {}
    for p in _all_pids():
        f = _stat_fields(p)
        if f and f[0] not in ("Z", "X"):
            children.setdefault(int(f[1]), []).append(p)
    out, todo = [], [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


def wait_gone(alive: Callable[[], bool], timeout: float, poll_s: float = 0.05) -> bool:
    """Poll ``alive()`` until it is false (True) or ``timeout`` seconds pass (False)."""
    deadline = time.monotonic() + timeout
    while alive():
        if time.monotonic() >= deadline:
            return False
        time.sleep(poll_s)
    return True


def stop_ladder(send: Callable[[int], None], alive: Callable[[], bool], term_timeout: float,
                kill_timeout: float = KILL_WAIT_S, *, first: int = signal.SIGTERM) -> str:
    """SIGTERM (or ``first``, e.g. SIGINT for a process whose clean shutdown is Ctrl-C), wait up to
    ``term_timeout`` for ``alive()`` to turn false, then SIGKILL and wait again.

    ``send(sig)`` signals whatever is being stopped (a group, a PID, several groups); ``alive()`` says
    whether any of it is left. Returns how it ended: "exited" (nothing to stop), "terminated" or "killed".
    """
    if not alive():
        return "exited"
    send(first)
    if wait_gone(alive, term_timeout):
        return "terminated"
    send(signal.SIGKILL)
    wait_gone(alive, kill_timeout)
    return "killed"


def stop_process(proc: subprocess.Popen[Any], term_timeout: float = 30.0, *, group: bool = False,
                 kill_timeout: float = KILL_WAIT_S, first: int = signal.SIGTERM) -> str:
    """Stop one child we started: its whole process group with ``group`` (it was started with
    ``start_new_session``), else just the process; reaps it. Same ladder and result as :func:`stop_ladder`."""
    if group:
        def send(sig: int) -> None:
            _signal_group(proc, signal.Signals(sig))

        def alive() -> bool:
            return proc.poll() is None or bool(group_members(proc.pid))
    else:
        def send(sig: int) -> None:
            with contextlib.suppress(ProcessLookupError):
                proc.send_signal(sig)

        def alive() -> bool:
            return proc.poll() is None
    return stop_ladder(send, alive, term_timeout, kill_timeout, first=first)


class ProcessGroups:
    """Spawns children in new sessions and tears their whole groups down on ``kill_all``."""

    def __init__(self) -> None:
        self._procs: list[subprocess.Popen[Any]] = []
        self._lock = threading.Lock()

    def spawn(self, cmd: str | Sequence[str], **popen_kwargs: Any) -> subprocess.Popen[Any]:
        """Start ``cmd`` (a string runs through ``bash -c``) as leader of a new process group."""
        if isinstance(cmd, str):
            cmd = ["bash", "-c", cmd]
        popen_kwargs["start_new_session"] = True  # its own group, so teardown reaches grandchildren
        proc = subprocess.Popen(list(cmd), **popen_kwargs)
        with self._lock:
            self._procs.append(proc)
        log.info("spawned pid %d: %s", proc.pid, " ".join(cmd))
        return proc

    @property
    def processes(self) -> list[subprocess.Popen[Any]]:
        """A snapshot of the children spawned and not yet torn down (safe to iterate while others spawn)."""
        with self._lock:
            return list(self._procs)

    def kill_all(self, grace_s: float = 5.0) -> None:
        """SIGTERM every group, wait up to ``grace_s``, then SIGKILL the groups still alive."""
        procs = self.processes

        def send(sig: int) -> None:
            for proc in procs:
                _signal_group(proc, signal.Signals(sig))

        def alive() -> bool:
            # The leader may be gone while others in its group live on: look at the whole group.
            return any(p.poll() is None or group_members(p.pid) for p in procs)

        if stop_ladder(send, alive, grace_s, kill_timeout=2.0) == "killed" and alive():
            log.warning("pids %s did not exit after SIGKILL", [p.pid for p in procs if p.poll() is None])
        with self._lock:
            self._procs = [p for p in self._procs if p not in procs]


def _signal_group(proc: subprocess.Popen[Any], sig: signal.Signals) -> None:
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass
    except PermissionError as exc:  # not our group (start_new_session=False): signal the child only
        log.debug("killpg(%d) refused (%s); signalling the process", proc.pid, exc)
        if proc.poll() is None:
            proc.send_signal(sig)
