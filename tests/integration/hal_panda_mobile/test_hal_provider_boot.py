"""``rbnx boot`` of a deploy holding just the HAL entry (the console script, a real atlas), then SIGINT:
the provider reaches ACTIVE, publishes /scan, and every recorded process is gone afterwards."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from support.boot import RbnxBoot
from support.procs import REPO, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.dds import DdsNode, LaserScan
from robonix_api.types import LifecycleState

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


def test_rbnx_boot_hal_only_and_sigint_leaves_nothing(tmp_path: Path) -> None:
    if shutil.which("bash") is None:
        pytest.skip("rbnx runs start: with bash")
    deploy = tmp_path / "deploy.yaml"
    deploy.write_text(DEPLOY.format(path=REPO / "hal_panda_mobile"))
    with RbnxBoot(deploy, tmp_path) as boot:
        boot.wait_ready(1)
        st = boot.state()
        with AtlasClient(st["atlas"]) as client:
            (prov,) = client.query(id="sim_base")
            assert prov.state == LifecycleState.ACTIVE

            def contracts() -> set[str]:
                (p,) = client.query(id="sim_base")
                return {c.contract_id for c in p.capabilities}

            # declared right after ACTIVATE answers: wait for them rather than sample once
            wanted = {"robonix/primitive/chassis/odom", "robonix/primitive/chassis/twist_in",
                      "robonix/primitive/lidar/lidar", "robonix/primitive/sim/teleport"}
            wait_until(lambda: wanted <= contracts(), 60,
                       lambda: f"{sorted(wanted)} declared (has {sorted(contracts())})")
        with DdsNode(name="boot_test") as node:
            scan = node.wait_for_message("/scan", LaserScan, 60, "best_effort")
            assert scan is not None
            assert len(scan.ranges) == 360

        boot.interrupt()
        assert "CMD_SHUTDOWN ok" in boot.output()
        boot.wait_all_exited()
        log = boot.log("sim_base")
        assert "Traceback" not in log, log[-3000:]
