"""rbnx's process helpers on real processes: a spawned group stops with its grandchildren, an entry that
ignores SIGTERM is killed, a hook that overruns its timeout is killed with its group."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from support.wait import wait_until

from rbnx.boot.procs import group_members, pid_alive, run_hook, spawn


def test_spawned_group_stops_with_grandchildren(tmp_path: Path) -> None:
    """A package's background children die with it; the PIDs are checked in /proc."""
    g = spawn("t", ["bash", "-c", "sleep 60 & sleep 60 & wait"], tmp_path, os.environ, tmp_path / "t.log")
    members: list[int] = []

    def three() -> bool:
        members[:] = group_members(g.pgid)
        return len(members) == 3

    wait_until(three, 30, lambda: f"three processes in the group, got {members}")
    assert g.stop(term_timeout=10) == "terminated"
    assert not any(pid_alive(p) for p in members)


def test_stop_escalates_to_kill(tmp_path: Path) -> None:
    code = ("import signal,time,sys; signal.signal(signal.SIGTERM, signal.SIG_IGN); print('up', flush=True); "
            "time.sleep(60)")
    g = spawn("t", [sys.executable, "-c", code], tmp_path, os.environ, tmp_path / "t.log")
    wait_until(lambda: "up" in (tmp_path / "t.log").read_text(), 30, "the child to ignore SIGTERM and say up")
    assert g.stop(term_timeout=0.5) == "killed"
    assert not pid_alive(g.pid)


def test_hook_timeout_kills_group(tmp_path: Path) -> None:
    ok, how = run_hook("h", "sleep 30", tmp_path, os.environ, None, timeout=0.5)
    assert not ok
    assert how == "timed out after 0.5s"
    assert run_hook("h", "exit 3", tmp_path, os.environ, None, timeout=30) == (False, "exit code 3")
