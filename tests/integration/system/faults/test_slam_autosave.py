"""Issue 16: the map survives a crash of the mapping service. Under a real `rbnx boot` of the sim deploy,
the robot maps part of the kitchen (one goal); mapping's session is autosaved (atomically, every 0.5 s of
new data) to <map_dir>/.autosave/<deployment>/mapping/; SIGKILL of mapping; rbnx boot restarts it with RBNX_RESTARTS=1
and it resumes from the autosave: the occupied cells of the map saved before the kill and of the map saved
after the restart overlap with IoU >= 0.95 (a restart without the autosave would start an empty map), and
a further goal succeeds on the resumed map."""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from support.e2e import grpc_endpoint, wait_until
from support.faults import occupied_iou

from robonix_api import auth
from robonix_api.atlas_client import AtlasClient
from robonix_api.mapfile import load_map_yaml
from robonix_api.proto_gen import map_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs
from robonix_api.types import LifecycleState
from robonix_common.grid import GridMap

from .faultutil import navigate, sim_boot

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(420)]

KITCHEN_GOAL = (5.8, 3.0)
BACK_GOAL = (3.2, 2.0)


def nodes_in(session_file: Path) -> int:
    """Pose-graph nodes in a session file (a half-written file cannot be seen: writes are atomic)."""
    with np.load(session_file) as z:
        return int(z["poses"].shape[0])


def save_map(atlas: str, map_id: str, map_dir: Path) -> GridMap:
    with AtlasClient(atlas) as client:
        ep = grpc_endpoint(client, "robonix/service/map/save_map")
    with auth.channel(ep) as ch:
        r = stubs.RobonixServiceMapSaveMapStub(ch).SaveMap(map_pb2.SaveMap_Request(map_id=map_id), timeout=60)
    assert r.ok, r.detail
    return load_map_yaml(map_dir / map_id / "map.yaml")


def test_mapping_sigkill_resumes_from_its_autosave_and_keeps_the_map(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    map_dir = tmp_path / "maps"
    autosaves = map_dir / ".autosave"  # <deployment>/mapping/session.npz: keyed by deployment (issue 37)
    with sim_boot(tmp_path, monkeypatch, ROBONIX_MAP_DIR=str(map_dir)) as run:
        atlas, state_file = run.atlas, run.state_file

        state, detail = navigate(atlas, *KITCHEN_GOAL, timeout_s=150)
        assert state == "SUCCEEDED", detail
        # the robot stands still now: wait until the autosave holds every node of the session saved now
        before = save_map(atlas, "before", map_dir)
        nodes = nodes_in(map_dir / "before" / "session.npz")
        def saved_all() -> bool:
            found = sorted(autosaves.glob("*/mapping/session.npz"))
            return len(found) == 1 and nodes_in(found[0]) == nodes

        wait_until(saved_all, 15, f"the autosave to hold all {nodes} nodes")
        assert (before.data >= 65).sum() > 200, "the robot mapped too little for a meaningful comparison"

        with AtlasClient(atlas) as client:
            old_reg = next(p.registration_id for p in client.query() if p.id == "mapping")
        old_pid = next(c["pid"] for c in json.loads(state_file.read_text())["children"] if c["name"] == "mapping")
        t_kill = time.monotonic()
        subprocess.run(["kill", "-KILL", str(old_pid)], check=True)

        def back() -> bool:
            with AtlasClient(atlas) as client:
                p = next((p for p in client.query() if p.id == "mapping"), None)
            return p is not None and p.registration_id != old_reg and p.state == LifecycleState.ACTIVE

        wait_until(back, 10, "mapping ACTIVE again", 0.05)
        print(f"mapping ACTIVE again {time.monotonic() - t_kill:.2f}s after SIGKILL")
        run.record_pids()
        log = (tmp_path / "logs" / "mapping.log").read_text()
        assert "restart 1: resumed the autosaved session" in log, log[-2000:]

        after = save_map(atlas, "after", map_dir)
        iou = occupied_iou(before, after)
        print(f"occupied-cell IoU before/after the crash: {iou:.3f} ({(before.data >= 65).sum()} / "
              f"{(after.data >= 65).sum()} cells)")
        assert iou >= 0.95

        state, detail = navigate(atlas, *BACK_GOAL, timeout_s=150)
        assert state == "SUCCEEDED", detail
