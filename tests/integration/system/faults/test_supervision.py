"""Issue 16 (process side), with real processes: `rbnx boot` of examples/sim/deploy.yaml (restart:
on-failure), then SIGKILL of each provider in turn: the atlas shows it TERMINATED within a second or
two (rbnx boot tells it; the heartbeat timeout is 90 s), it is started again, every provider is ACTIVE
again within 10 s of the kill, the restart is counted in the state file and `rbnx caps`, the next goal
succeeds, and after SIGINT no process of any run (first or restarted) is left.

The HAL is killed first, while the robot still stands at its start pose: a restarted simulator starts
from that pose again, so the map stays consistent with it. Times are measured, and the bounds are
generous multiples of what a loaded 2-core machine shows (TERMINATED ~0.1 s, all ACTIVE ~3 s).
"""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import pytest
from support.e2e import rbnx_cmd, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.procs import pid_alive
from robonix_api.types import LifecycleState

from .faultutil import navigate, sim_boot

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(420)]

ENTRIES = ("panda_mobile", "mapping", "nav2")
KITCHEN_GOAL = (5.8, 3.0)
TERMINATED_WITHIN_S = 2.0
RECOVERED_WITHIN_S = 10.0


def _states(atlas: str) -> dict[str, tuple[LifecycleState, str]]:
    with AtlasClient(atlas) as client:
        return {p.id: (p.state, p.registration_id) for p in client.query() if p.id in ENTRIES}


def _children(state_file: Path) -> dict[str, dict]:
    return {c["name"]: c for c in json.loads(state_file.read_text())["children"]}


def test_sigkill_of_each_provider_is_seen_at_once_restarted_and_the_next_goal_succeeds(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with sim_boot(tmp_path, monkeypatch) as run:
        atlas, state_file, env = run.atlas, run.state_file, run.env

        for name in ENTRIES:
            before = _states(atlas)
            assert all(s == LifecycleState.ACTIVE for s, _ in before.values()), before
            old = _children(state_file)[name]
            t_kill = time.monotonic()
            subprocess.run(["kill", "-KILL", str(old["pid"])], check=True)

            wait_until(lambda name=name: _states(atlas)[name][0] == LifecycleState.TERMINATED,
                       TERMINATED_WITHIN_S, f"{name} TERMINATED on the atlas", 0.02)
            t_term = time.monotonic() - t_kill

            def recovered(name: str = name, old_reg: str = before[name][1]) -> bool:
                now = _states(atlas)
                return (now[name][1] != old_reg
                        and all(s == LifecycleState.ACTIVE for s, _ in now.values()))

            wait_until(recovered, RECOVERED_WITHIN_S, f"all ACTIVE again after killing {name}", 0.05)
            t_rec = time.monotonic() - t_kill
            print(f"{name}: TERMINATED on the atlas after {t_term:.2f}s, all ACTIVE after {t_rec:.2f}s")
            new = _children(state_file)[name]
            assert new["pid"] != old["pid"], new
            assert new["restarts"] == 1, new
            assert not pid_alive(old["pid"], old["start_ticks"])
            run.record_pids()
            assert f"{name} killed by signal 9; marked TERMINATED" in run.output()
            # the restarted process was told it is a restart
            env_of = Path(f"/proc/{new['pid']}/environ").read_bytes().split(b"\0")
            assert b"RBNX_RESTARTS=1" in env_of, f"{name}: RBNX_RESTARTS=1 not in its environment"

        caps = subprocess.run(rbnx_cmd() + ["--atlas", atlas, "caps"], env=env, capture_output=True, text=True,
                              timeout=60)
        assert caps.returncode == 0, caps.stderr
        for name in ENTRIES:
            line = next(ln for ln in caps.stdout.splitlines() if ln.startswith(f"{name} "))
            assert "ACTIVE" in line.upper(), caps.stdout
            assert "restarts 1" in line, caps.stdout

        state, detail = navigate(atlas, *KITCHEN_GOAL, timeout_s=150)
        assert state == "SUCCEEDED", detail
