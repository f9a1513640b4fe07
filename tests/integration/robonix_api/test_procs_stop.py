"""The one SIGTERM → wait → SIGKILL ladder (robonix_api.procs), on real child processes."""

from __future__ import annotations

import subprocess
import sys

from robonix_api.procs import ProcessGroups, group_members, pid_alive, stop_ladder, stop_process

# Ignores SIGTERM in itself and in a grandchild (SIG_IGN survives exec), then says it is ready.
_STUBBORN = "trap '' TERM; sleep 60 & echo ready; wait"


def _ready(proc: subprocess.Popen[str]) -> None:
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "ready"


def test_group_that_ignores_term_is_killed_with_its_grandchild() -> None:
    proc = subprocess.Popen(["bash", "-c", _STUBBORN], stdout=subprocess.PIPE, text=True, start_new_session=True)
    _ready(proc)
    members = group_members(proc.pid)
    assert len(members) >= 2  # bash and its sleep
    assert stop_process(proc, 0.5, group=True) == "killed"
    assert proc.returncode is not None
    assert not [p for p in members if pid_alive(p)]
    proc.stdout.close()


def test_polite_child_is_terminated_and_a_gone_one_exited() -> None:
    proc = subprocess.Popen([sys.executable, "-c", "import time; print('ready', flush=True); time.sleep(60)"],
                            stdout=subprocess.PIPE, text=True)
    _ready(proc)
    assert stop_process(proc, 30.0) == "terminated"
    assert proc.returncode == -15
    assert stop_process(proc, 30.0) == "exited"
    proc.stdout.close()


def test_ladder_sends_kill_only_when_term_was_not_enough() -> None:
    sent: list[int] = []
    state = {"alive": True}

    def send(sig: int) -> None:
        sent.append(sig)
        state["alive"] = sig != 15  # dies on TERM

    assert stop_ladder(send, lambda: state["alive"], 1.0) == "terminated"
    assert sent == [15]
    sent.clear()
    state["alive"] = True
    assert stop_ladder(lambda sig: sent.append(sig), lambda: state["alive"], 0.1, kill_timeout=0.1) == "killed"
    assert sent == [15, 9]


def test_process_groups_kill_all_reaches_grandchildren() -> None:
    groups = ProcessGroups()
    proc = groups.spawn(_STUBBORN, stdout=subprocess.PIPE, text=True)
    _ready(proc)
    members = group_members(proc.pid)
    groups.kill_all(grace_s=0.5)
    assert not [p for p in members if pid_alive(p)]
    assert groups.processes == []
    proc.stdout.close()
