"""Supervision details on the light example deploy (no simulator): a provider paused (INACTIVE) when it
is killed comes back INACTIVE, not ACTIVE; `restart_max` bounds consecutive restarts (then the entry is
left TERMINATED on the atlas and the boot says it gave up); `restart: never` is not restarted."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from support.e2e import e2e_env, wait_until

from rbnx.atlas_rpc import CMD, Atlas, Driver, driver_capability
from robonix_api.types import LifecycleState

from .faultutil import booted

pytestmark = [pytest.mark.integration, pytest.mark.timeout(240)]

MINIMAL = Path(__file__).resolve().parents[4] / "examples" / "minimal"


def _deploy(tmp: Path) -> Path:
    f = tmp / "deploy.yaml"
    f.write_text(f"""manifestVersion: 1
name: restart-state
env:
  ROBONIX_HEARTBEAT_PERIOD_S: "5"
system:
  atlas:
    listen: ${{RBNX_ATLAS_LISTEN:-127.0.0.1:50051}}
primitive:
  - name: odom_primitive
    path: {MINIMAL / 'odom_primitive'}
    restart: on-failure
    restart_max: 1
    restart_backoff_s: 0.2
    config: {{topic: /odom}}
service:
  - name: odom_consumer
    path: {MINIMAL / 'odom_consumer'}
    restart: on-failure
    config: {{provider_ids: {{odom: odom_primitive}}}}
""")
    return f


def _prov(atlas: str, name: str):
    with Atlas(atlas, timeout=5.0) as a:
        return a.provider(name)


def _pid(state_file: Path, name: str) -> int:
    return next(c["pid"] for c in json.loads(state_file.read_text())["children"] if c["name"] == name)


def test_inactive_comes_back_inactive_and_restart_max_gives_up(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with booted(tmp_path, monkeypatch, _deploy(tmp_path), 2, e2e_env(tmp_path)) as run:
        atlas, state_file, out = run.atlas, run.state_file, run.out

        # pause the consumer, then kill it: it must come back paused (INACTIVE), as it was
        with Atlas(atlas, timeout=5.0) as a:
            prov = a.provider("odom_consumer")
            endpoint, params = a.endpoint("odom_consumer", driver_capability(prov) or "", 1)
        drv = Driver(endpoint, params)
        assert drv.call(CMD.CMD_DEACTIVATE, None, 10.0).ok
        drv.close()
        assert _prov(atlas, "odom_consumer").state == LifecycleState.INACTIVE
        old_reg = _prov(atlas, "odom_consumer").registration_id
        subprocess.run(["kill", "-KILL", str(_pid(state_file, "odom_consumer"))], check=True)
        wait_until(lambda: (p := _prov(atlas, "odom_consumer")) is not None and p.registration_id != old_reg
                   and p.state == LifecycleState.INACTIVE and "odom_consumer restarted (inactive" in out.read_text(),
                   20, "odom_consumer back INACTIVE")
        run.record_pids()
        assert "odom_consumer (service): inactive(restarts 1)" in out.read_text()

        # restart_max 1: the first kill is restarted, the second (right after) is not
        subprocess.run(["kill", "-KILL", str(_pid(state_file, "odom_primitive"))], check=True)
        wait_until(lambda: "odom_primitive restarted (active, restart 1" in out.read_text(), 20,
                   "odom_primitive restarted once")
        run.record_pids()
        subprocess.run(["kill", "-KILL", str(_pid(state_file, "odom_primitive"))], check=True)
        wait_until(lambda: "odom_primitive killed by signal 9; marked TERMINATED on the atlas; not restarted "
                   "(gave up after 1 restarts" in out.read_text(), 20, "odom_primitive given up")
        assert _prov(atlas, "odom_primitive").state == LifecycleState.TERMINATED
        assert run.proc.poll() is None  # the boot itself carries on
