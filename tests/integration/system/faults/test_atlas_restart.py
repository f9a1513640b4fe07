"""Issue 16: SIGKILL of the atlas under a real `rbnx boot` of the sim deploy (system.atlas.restart:
on-failure). rbnx boot starts it again on the same address; every provider notices the new atlas
through its connection watch and re-registers with its capabilities and its ACTIVE state within a few
seconds (not at its next heartbeat); the restart is counted in the state file; nothing is left after
SIGINT. (Whether navigation's bindings survive the restart is the data-plane side, tested with it.)"""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import pytest
from support.procs import wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.types import LifecycleState

from .faultutil import sim_boot

pytestmark = [pytest.mark.integration, pytest.mark.timeout(300)]

ENTRIES = ("panda_mobile", "mapping", "nav2")
REREGISTERED_WITHIN_S = 3.0  # the deploy heartbeats every 5 s: only the connection watch meets this


def _active(atlas: str) -> set[str]:
    try:
        with AtlasClient(atlas) as client:
            return {p.id for p in client.query() if p.state == LifecycleState.ACTIVE and len(p.capabilities) > 1}
    except Exception:
        return set()


def test_atlas_sigkill_is_restarted_and_every_provider_re_registers_active(tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    with sim_boot(tmp_path, monkeypatch) as run:
        st = run.state()
        atlas = run.atlas
        assert _active(atlas) == set(ENTRIES)

        t_kill = time.monotonic()
        subprocess.run(["kill", "-KILL", str(st["atlas_proc"]["pid"])], check=True)
        wait_until(lambda: "atlas restarted (restart 1" in run.output(), 15, "the atlas restart")
        t_up = time.monotonic() - t_kill
        wait_until(lambda: _active(atlas) == set(ENTRIES), REREGISTERED_WITHIN_S,
                   "every provider ACTIVE on the new atlas", 0.05)
        t_all = time.monotonic() - t_kill
        print(f"atlas back after {t_up:.2f}s, all providers ACTIVE on it after {t_all:.2f}s")
        new = run.state()["atlas_proc"]
        assert new["pid"] != st["atlas_proc"]["pid"], new
        assert new["restarts"] == 1, new
        run.record_pids()
        for name in ENTRIES:
            assert "re-registered" in (tmp_path / "logs" / f"{name}.log").read_text(), name
