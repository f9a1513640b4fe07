"""Issue 16: the atlas killed and started again while the robot drives a goal. DDS data never stops, the
providers re-register on their next heartbeat, and the goal must still SUCCEED (it used to fail with
"provider 'mapping' left the atlas (map lost)" 2.6 s after the new atlas came up)."""

from __future__ import annotations

import signal
from pathlib import Path

import pytest
from support.faults import KITCHEN, Recorder, SimBoot, signal_pid
from support.procs import alive, wait_until

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(420)]


def test_atlas_restart_during_a_goal_goal_succeeds(tmp_path: Path) -> None:
    with SimBoot(tmp_path) as boot:
        run_id = boot.navigate(*KITCHEN["pantry"])
        rec = Recorder(boot, run_id).start()
        try:
            wait_until(rec.moving, 90, "the robot to drive the goal")
            atlas_pid = boot.pids()["atlas"]
            signal_pid(atlas_pid, signal.SIGKILL)
            wait_until(lambda: not alive(atlas_pid), 30, "the killed atlas to be gone")
            boot.ensure_atlas(5.0)   # the boot's restart: on-failure, else we start one at the address
            wait_until(boot.all_active, 60, lambda: f"providers re-registered: {boot.states()}", 0.2)
            state, detail = boot.wait_terminal(run_id, 180)
        finally:
            rec.stop()
        assert state == "SUCCEEDED", detail
        assert not any(s.state == "FAILED" for s in rec.samples)
        assert boot.shutdown() == []
