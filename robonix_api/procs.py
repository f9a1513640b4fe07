"""Child processes a provider starts (``svc.spawn``), each in its own process group.

A provider that wraps other programs (a simulator, a bridge) must not leave them behind: teardown
signals every group with SIGTERM, waits, then SIGKILLs what is left, as robonix does.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
import threading
import time
from collections.abc import Sequence
from typing import Any

log = logging.getLogger(__name__)


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
        with self._lock:
            return list(self._procs)

    def kill_all(self, grace_s: float = 5.0) -> None:
        """SIGTERM every group, wait up to ``grace_s``, then SIGKILL the groups still alive."""
        procs = self.processes
        for proc in procs:
            _signal_group(proc, signal.SIGTERM)
        deadline = time.monotonic() + grace_s
        for proc in procs:
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(max(0.0, deadline - time.monotonic()))
        for proc in procs:
            # The leader may be gone while others in its group live on: always KILL the group.
            _signal_group(proc, signal.SIGKILL)
            try:
                proc.wait(2.0)
            except subprocess.TimeoutExpired:
                log.warning("pid %d did not exit after SIGKILL", proc.pid)
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
