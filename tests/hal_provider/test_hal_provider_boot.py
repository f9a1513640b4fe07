"""``rbnx boot`` of a deploy holding just the HAL entry (the console script, a real atlas), then SIGINT:
the provider reaches ACTIVE, publishes /scan, and every recorded process is gone afterwards."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from robonix_api.atlas_client import AtlasClient
from robonix_api.dds import DdsNode, LaserScan
from robonix_api.types import LifecycleState

from .conftest import REPO, alive, wait_until

pytestmark = pytest.mark.integration

DEPLOY = """\
manifestVersion: 1
name: hal_only
env:
  ROBONIX_HEARTBEAT_PERIOD_S: "2"
system:
  atlas:
    listen: ${{RBNX_ATLAS_LISTEN:-127.0.0.1:0}}
primitive:
  - name: sim_base
    path: {path}
    config:
      scene: warehouse
      real_time_factor: 1.0
"""


def _rbnx() -> list[str]:
    exe = Path(sys.executable).parent / "rbnx"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]


def test_rbnx_boot_hal_only_and_sigint_leaves_nothing(tmp_path: Path) -> None:
    if shutil.which("bash") is None:
        pytest.skip("rbnx runs start: with bash")
    deploy = tmp_path / "deploy.yaml"
    deploy.write_text(DEPLOY.format(path=REPO / "hal_panda_mobile"))
    env = dict(os.environ, RBNX_STATE_DIR=str(tmp_path / "state"), RBNX_ATLAS_LISTEN="127.0.0.1:0",
               RBNX_PYTHON=sys.executable, PYTHONUNBUFFERED="1")
    for name in ("ROBONIX_ATLAS", "RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED"):
        env.pop(name, None)
    out = tmp_path / "boot.out"
    with open(out, "w") as fh:
        proc = subprocess.Popen(_rbnx() + ["boot", "-f", str(deploy), "--log-dir", str(tmp_path / "logs")],
                                env=env, cwd=tmp_path, stdout=fh, stderr=subprocess.STDOUT)
    try:
        def ready() -> bool:
            text = out.read_text()
            if proc.poll() is not None:
                raise AssertionError(f"rbnx boot exited {proc.returncode}:\n{text}")
            return "1/1 entries ready" in text

        wait_until(ready, 180, "boot summary", 0.2)
        (state_file,) = (tmp_path / "state").glob("boot-*.json")
        st = json.loads(state_file.read_text())
        pids = [st["pid"], st["atlas_proc"]["pid"], *(c["pid"] for c in st["children"])]
        with AtlasClient(st["atlas"]) as client:
            (prov,) = client.query(id="sim_base")
            assert prov.state == LifecycleState.ACTIVE
            contracts = {c.contract_id for c in prov.capabilities}
            assert {"robonix/primitive/chassis/odom", "robonix/primitive/chassis/twist_in",
                    "robonix/primitive/lidar/lidar", "robonix/primitive/sim/teleport"} <= contracts
        with DdsNode(name="boot_test") as node:
            scan = node.wait_for_message("/scan", LaserScan, 60, "best_effort")
            assert scan is not None and len(scan.ranges) == 360

        proc.send_signal(signal.SIGINT)
        assert proc.wait(180) == 0, out.read_text()
        assert "CMD_SHUTDOWN ok" in out.read_text()
        wait_until(lambda: not any(alive(p) for p in pids), 30, "every recorded process to exit")
        log = (tmp_path / "logs" / "sim_base.log").read_text()
        assert "Traceback" not in log, log[-3000:]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
