"""Issue 16: SIGKILL of the atlas under a real `rbnx boot` of the sim deploy (system.atlas.restart:
on-failure). rbnx boot starts it again on the same address; every provider notices the new atlas
through its connection watch and re-registers with its capabilities and its ACTIVE state within a few
seconds (not at its next heartbeat); the restart is counted in the state file; nothing is left after
SIGINT. (Whether navigation's bindings survive the restart is the data-plane side, tested with it.)"""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import pytest
from e2e.conftest import SIM_DEPLOY, alive, e2e_env, rbnx_cmd, recorded_pids, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.types import LifecycleState

from .faultutil import adopt_token

pytestmark = [pytest.mark.integration, pytest.mark.timeout(300)]

ENTRIES = ("panda_mobile", "mapping", "nav2")
REREGISTERED_WITHIN_S = 3.0  # the deploy heartbeats every 5 s: only the connection watch meets this


def _active(atlas: str) -> set[str]:
    try:
        with AtlasClient(atlas) as client:
            return {p.id for p in client.query() if p.state == LifecycleState.ACTIVE and len(p.capabilities) > 1}
    except Exception:  # noqa: BLE001 (the atlas is down or starting)
        return set()


def test_atlas_sigkill_is_restarted_and_every_provider_re_registers_active(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    env = e2e_env(tmp_path, RBNX_SIM_SCENE="kitchen", RBNX_SIM_RTF="2")
    out = tmp_path / "boot.out"
    with open(out, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(SIM_DEPLOY), "--no-progress", "--no-gateway",
                                              "--log-dir", str(tmp_path / "logs")],
                                env=env, cwd=tmp_path, stdout=fh, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
    every_pid: set[tuple[str, int, int | None]] = set()
    try:
        wait_until(lambda: proc.poll() is None and "3/3 entries ready" in out.read_text(), 150, "boot summary")
        (state_file,) = (tmp_path / "state").glob("boot-*.json")
        adopt_token(state_file, monkeypatch)
        st = json.loads(state_file.read_text())
        atlas = st["atlas"]
        every_pid.update(recorded_pids(state_file))
        assert _active(atlas) == set(ENTRIES)

        t_kill = time.monotonic()
        subprocess.run(["kill", "-KILL", str(st["atlas_proc"]["pid"])], check=True)
        wait_until(lambda: "atlas restarted (restart 1" in out.read_text(), 15, "the atlas restart")
        t_up = time.monotonic() - t_kill
        wait_until(lambda: _active(atlas) == set(ENTRIES), REREGISTERED_WITHIN_S,
                   "every provider ACTIVE on the new atlas", 0.05)
        t_all = time.monotonic() - t_kill
        print(f"atlas back after {t_up:.2f}s, all providers ACTIVE on it after {t_all:.2f}s")
        new = json.loads(state_file.read_text())["atlas_proc"]
        assert new["pid"] != st["atlas_proc"]["pid"] and new["restarts"] == 1, new
        every_pid.update(recorded_pids(state_file))
        for name in ENTRIES:
            assert "re-registered" in (tmp_path / "logs" / f"{name}.log").read_text(), name
    finally:
        if proc.poll() is None:
            proc.send_signal(2)
            try:
                proc.wait(120)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)
    assert proc.returncode == 0, out.read_text()[-3000:]
    wait_until(lambda: not any(alive(p, t) for _, p, t in every_pid), 30, "every process of every run to exit")
