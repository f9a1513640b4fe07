"""``rbnx boot`` of a deploy listing the SLAM service *before* the HAL: SLAM answers Deferred (no lidar
yet), then comes up ACTIVE once the HAL is there; /map reaches a late DDS subscriber (latched) and TF
map->odom is published. SIGINT then leaves no recorded process behind."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml
from support.boot import RbnxBoot
from support.procs import REPO, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.dds import DdsNode, OccupancyGrid, TfBuffer
from robonix_api.types import LifecycleState

from .conftest import HAL_CONFIG

pytestmark = pytest.mark.integration


def test_boot_slam_before_hal_defers_then_serves_map(tmp_path: Path) -> None:
    if shutil.which("bash") is None:
        pytest.skip("rbnx runs start: with bash")
    deploy = {
        "manifestVersion": 1, "name": "slam_boot",
        "env": {"ROBONIX_HEARTBEAT_PERIOD_S": "2"},
        "system": {"atlas": {"listen": "${RBNX_ATLAS_LISTEN:-127.0.0.1:0}"}},
        # sections boot in file order: the service section comes first, so SLAM is asked before the HAL runs
        "service": [{"name": "mapping", "path": str(REPO / "slam_service"),
                     "config": {"map_dir": str(tmp_path / "maps"), "map_publish_period_s": 0.5}}],
        "primitive": [{"name": "sim_base", "path": str(REPO / "hal_panda_mobile"), "config": HAL_CONFIG}],
    }
    path = tmp_path / "deploy.yaml"
    path.write_text(yaml.safe_dump(deploy, sort_keys=False))
    assert path.read_text().index("service:") < path.read_text().index("primitive:")
    # --serial: SLAM starts alone, so it must answer Deferred (in parallel the HAL may already be up)
    with RbnxBoot(path, tmp_path, "--serial") as boot:
        boot.wait_ready(2)
        text = boot.output()
        assert "waiting for robonix/primitive/lidar/lidar" in text, text
        st = boot.state()
        with AtlasClient(st["atlas"]) as client:
            (prov,) = client.query(id="mapping")
            assert prov.state == LifecycleState.ACTIVE

            def declared() -> set[str]:
                (p,) = client.query(id="mapping")
                return {c.contract_id for c in p.capabilities}

            # the provider declares its outputs right after ACTIVATE answers: wait for it, not a timing
            wait_until(lambda: "robonix/service/map/occupancy_grid" in declared(), 60,
                       lambda: f"occupancy_grid declared by mapping (has {sorted(declared())})")
        with DdsNode(name="slam_boot_test") as node:
            tf = TfBuffer(node)
            try:
                assert tf.wait_for_transform("map", "odom", None, 60), "no TF map->odom"
            finally:
                tf.close()
            # a subscriber created after the map was published still gets it (transient_local)
            grid = node.wait_for_message("/map", OccupancyGrid, 60, "latched")
            assert grid is not None
            assert grid.header.frame_id == "map"
            assert grid.info.width * grid.info.height == len(grid.data) > 100

        boot.interrupt()
        boot.wait_all_exited()
        log = boot.log("mapping")
        assert "CMD_INIT deferred" in log, log[-3000:]
        assert "Traceback" not in log, log[-3000:]
